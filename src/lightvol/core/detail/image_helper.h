// lightvol-image, the image decoder and encoder program: the only part of lightvol that links
// OpenImageIO (and through it GDAL, OpenVDB, ffmpeg, ...), so that a command that reads or writes
// no image never loads those libraries. The library starts it by posix_spawn when it first reads
// or writes an image (core/detail/isolated.h IsolatedServer: a fresh process, limits of its own
// for each request) and keeps it for the next request; requests and answers go over a socket
// pair. Internal to the library: the depth
// stage reads images through it (depth/detail/image_file.h), the depth and render stages write
// images through write_image_file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <lightvol/core/detail/isolated.h>
#include <lightvol/core/result.h>

namespace lightvol::detail {

// The first byte of a request.
enum class ImageRequest : std::uint8_t { read = 'R', write = 'W', vdb = 'V' };

// The program's path, the first of these that is an executable file: $LIGHTVOL_IMAGE_HELPER;
// lightvol-image beside the running executable (/proc/self/exe); ../libexec/lightvol/ relative
// to it; the installed libexec directory; the build tree's. An Error saying where it looked
// otherwise.
Result<std::string> image_helper_path();

// Serves one request on `channel` (what lightvol-image's main does); `threads` is the decoder's
// thread count (0: every core).
using ImageServer = bool (*)(ChildOutput& channel, int threads);

// The programs that serve image requests: lightvol-image (OpenImageIO, every request), and
// lightvol-exr, which links OpenEXR alone (a few libraries to load instead of about 260) and reads
// only plain EXR depth maps, declining every other file (depth/detail/exr_codec.h): the depth
// stage tries it first for an EXR file, then lightvol-image.
enum class ImageProgram : std::uint8_t { image = 0, exr = 1 };

// lightvol-exr's path, as image_helper_path finds lightvol-image's ($LIGHTVOL_EXR_HELPER instead of
// $LIGHTVOL_IMAGE_HELPER); none when it is not found, or when $LIGHTVOL_IMAGE_HELPER is set and
// $LIGHTVOL_EXR_HELPER is not (that program is then to serve every read).
std::optional<std::string> exr_helper_path();

// Whether a read of an EXR file should go to lightvol-exr first: its in-process server is set, or
// (no in-process image server) the program is found.
bool exr_helper_available();

// Runs `parent` (which sends the request and reads the answer) against a fresh lightvol-image,
// with `limits` (run_isolated_program); or, when this process serves images itself
// (set_in_process_image_server), against a forked child running that server on one thread
// (run_isolated). Errors name `what`.
Status run_image_helper(const std::string& what, const IsolationLimits& limits,
                        const std::function<Status(ChildInput&)>& parent,
                        ImageProgram program = ImageProgram::image);

// For programs that link the decoder (the fuzz targets, whose coverage must include it, and
// which read thousands of inputs): images are then read in a forked child of this process, as
// before lightvol-image existed, not by starting the program. nullptr restores the program.
void set_in_process_image_server(ImageServer server);
// The same for lightvol-exr's server (the fuzz targets). Without it, a process with an in-process
// image server never tries lightvol-exr.
void set_in_process_exr_server(ImageServer server);

// A reader's destination for the floats of one read (lightvol-image's and lightvol-exr's side of
// the conversation): the parent's shared memory when it offered a memfd of exactly `texels` floats
// (mapped here; the descriptor is closed), else a buffer of the reader's own, not zeroed (the
// decoder writes every float).
class DecodedFloats {
 public:
  DecodedFloats(int shared_fd, std::size_t texels);
  ~DecodedFloats() { unmap(); }
  DecodedFloats(const DecodedFloats&) = delete;
  DecodedFloats& operator=(const DecodedFloats&) = delete;
  float* data() const { return values_; }
  // No writable mapping may remain once the parent seals the memory against writes: called before
  // the reader answers (the floats stay readable only when they are the reader's own).
  void unmap();
  // After the read's last verdict: whether the floats are in the shared memory, and when not, the
  // floats themselves.
  void send(ChildOutput& channel) const;

 private:
  std::size_t bytes_ = 0;
  float* values_ = nullptr;
  bool shared_ = false;
  std::unique_ptr<float[]> own_;
};

// Ends the idle lightvol-image servers (the next request starts a fresh one): for tests that
// change LIGHTVOL_IMAGE_HELPER.
void close_idle_image_servers();

// An image to write: `channels` values per texel, rows top to bottom, as floats or 8-bit values;
// stored as `stored` (the file's type), with these channel names (empty: the format's).
struct ImageWrite {
  enum class Stored : std::uint8_t { f32 = 0, u8 = 1, u16 = 2 };
  int width = 0;
  int height = 0;
  int channels = 1;
  Stored stored = Stored::f32;
  std::vector<std::string> names;
  const float* floats = nullptr;        // width × height × channels floats, or
  const std::uint8_t* bytes = nullptr;  // as many 8-bit values
};

// How a write ended: written, no writer for the format `create_name`'s extension names, or the
// writer failed; `message` is OpenImageIO's (or why the program failed).
struct ImageWriteResult {
  enum class Outcome : std::uint8_t {
    written = 0,
    no_writer = 1,
    failed = 2
  } outcome = Outcome::written;
  std::string message;
};

// Writes `image` to the file `temp` in the format of `create_name`'s extension, through
// lightvol-image. A program that cannot be started or dies is `failed` with its Error's message.
ImageWriteResult write_image_file(const std::string& create_name, const std::string& temp,
                                  const ImageWrite& image);

}  // namespace lightvol::detail

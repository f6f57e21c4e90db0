// Opening image files for input a user or a script may have forged. Internal to the depth stage:
// read_depth_image and read_first_channel (depth_image.h), through read_image_channel, are the
// entry points. lightvol's own checks of the file run here; OpenImageIO runs in lightvol-image
// (core/detail/image_helper.h), whose side of the conversation is image_codec.h.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <lightvol/core/result.h>
#include <lightvol/depth/image_channel.h>

namespace lightvol::detail {

// What OpenImageIO's header says about an image, as far as lightvol's choices need it.
struct ImageHeader {
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::int32_t alpha_channel = -1;              // -1: none
  bool eight_bit = false;                       // the image's (first) format is 8-bit
  std::vector<std::string> names;               // one per channel
  std::vector<std::uint8_t> channel_eight_bit;  // per channel: 1 if stored in 8 bits
  int nchannels() const { return static_cast<int>(names.size()); }
};
constexpr int kMaxImageChannels = 1024;

// lightvol's own look at the file before any third-party code reads it: anything but a regular
// file; a format other than EXR, TIFF, PNG, PFM/PGM, HDR and ZFile (by magic bytes, else by
// extension: OpenImageIO's own open() would try every plugin it has, video and camera-raw
// decoders included, on a file its extension's plugin cannot open); EXR and PNG headers whose
// sizes run past the file.
struct ImageFile {
  std::string format;  // OpenImageIO's plugin name
  std::string magic;   // the file's first bytes
};
Result<ImageFile> check_image_file(const std::string& path);

// The size an EXR file's header gives (its data window), by lightvol's own reading of the header
// (single-part scanline or tiled files, the attribute within the first 64 KiB); nothing when the
// file is not such an EXR or the attribute is not found. A hint only (peek_image_size).
std::optional<std::array<int, 2>> exr_data_window_size(const std::string& path);

// Opens the image at `path` (check_image_file, then OpenImageIO's open and the checks of the
// header it read, image_codec.h), lets `within_budget(header)` refuse it (the caller's memory
// check) and `select(header)` pick the channel to read (or refuse the image with an Error), and
// reads it as floats: all of it in lightvol-image, a process of its own, since OpenImageIO 2.4's
// readers and the libraries behind them are not hardened against forged files (OpenImageIO's own
// fuzzing began in 2026 and found, among others, a heap overflow in its TIFF reader). A crash,
// more than 5 s of processor time for the header (then 2 s and 200 ns per texel for the pixels),
// or memory beyond the budget is an Error naming the file; so is a pixel read that fails, as
// "<path>: <read_failure>: <OpenImageIO's message>".
Result<ImageChannel> read_image_channel(
    const std::string& path, const std::function<Status(const ImageHeader&)>& within_budget,
    const std::function<Result<int>(const ImageHeader&)>& select, const std::string& read_failure);

// Whether reads offer lightvol-image a memfd to decode into (the default; read_image_channel falls
// back to the channel where memfd_create fails): off, the floats come through the channel, as
// where the kernel has no memfd. For tests of that path.
void offer_shared_memory(bool offer);

// OpenImageIO's error queue as one line.
std::string oiio_message(const std::string& message);

}  // namespace lightvol::detail

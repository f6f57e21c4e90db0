// Opening image files through OpenImageIO for input a user or a script may have forged. Internal
// to the depth stage (it names OpenImageIO types): read_depth_image and read_first_channel
// (depth_image.h), through read_image_channel, are the entry points.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include <lightvol/core/result.h>
#include <lightvol/depth/image_channel.h>

namespace lightvol::detail {

struct OpenImage {
  std::unique_ptr<OIIO::ImageInput> input;
  OIIO::ImageSpec spec;
};

// Opening an image in two steps, refusing before any pixel is allocated. check_image_file is
// lightvol's own look at the file before any third-party code reads it: anything but a regular
// file; a format other than EXR, TIFF, PNG, PFM/PGM, HDR and ZFile (by magic bytes, else by
// extension: OpenImageIO's own open() would try every plugin it has, video and camera-raw
// decoders included, on a file its extension's plugin cannot open); EXR and PNG headers whose
// sizes run past the file. open_checked_image is OpenImageIO's open and the checks of the header
// it reads: fewer than 2×2 texels, volumes and deep images; more than 2^30 texels;
// `within_budget(spec)` failing (the caller's memory check); a header promising more decoded
// bytes than the file can hold.
struct ImageFile {
  std::string format;  // OpenImageIO's plugin name
  std::string magic;   // the file's first bytes
};
Result<ImageFile> check_image_file(const std::string& path);
Result<OpenImage> open_checked_image(
    const std::string& path, const ImageFile& file,
    const std::function<Status(const OIIO::ImageSpec&)>& within_budget);

// Opens the image at `path` (check_image_file, then open_checked_image), lets `select(spec)` pick
// the channel to read (or refuse the image with an Error), and reads it as floats: all of it in a
// child process (core/isolated.h), since OpenImageIO 2.4's readers and the libraries behind them
// are not hardened against forged files (OpenImageIO's own fuzzing began in 2026 and found, among
// others, a heap overflow in its TIFF reader). A crash, more than 5 s of processor time for the
// header (then 2 s and 200 ns per texel for the pixels), or memory beyond the budget is an Error
// naming the file; so is a pixel read that fails, as "<path>: <read_failure>: <OpenImageIO's
// message>".
Result<ImageChannel> read_image_channel(
    const std::string& path, const std::function<Status(const OIIO::ImageSpec&)>& within_budget,
    const std::function<Result<int>(const OIIO::ImageSpec&)>& select,
    const std::string& read_failure);

// OpenImageIO's error queue as one line.
std::string oiio_message(const std::string& message);

}  // namespace lightvol::detail

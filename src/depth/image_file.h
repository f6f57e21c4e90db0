// Opening image files through OpenImageIO for input a user or a script may have forged. Internal
// to the library (it names OpenImageIO types): read_depth_image and read_image are the entry points.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include <OpenImageIO/imageio.h>

#include <lightvol/core/result.h>

namespace lightvol::detail {

struct OpenImage {
  std::unique_ptr<OIIO::ImageInput> input;
  OIIO::ImageSpec spec;
};

// Opens the image at `path` and reads its header, refusing before any pixel is allocated:
// anything but a regular file; a format other than EXR, TIFF, PNG, PFM/PGM, HDR and ZFile (by
// magic bytes, else by extension: OpenImageIO's own open() would try every plugin it has, video
// and camera-raw decoders included, on a file its extension's plugin cannot open); EXR and PNG
// headers whose sizes run past the file; fewer than 2×2 texels, volumes and deep images; more
// than 2^30 texels; `within_budget(spec)` failing (the caller's memory check); and a header
// promising more decoded bytes than the file can hold.
Result<OpenImage> open_image(const std::string& path,
                             const std::function<Status(const OIIO::ImageSpec&)>& within_budget);

// OpenImageIO's error queue as one line.
std::string oiio_message(const std::string& message);

}  // namespace lightvol::detail

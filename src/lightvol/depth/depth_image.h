// Depth images: what a shadow-map render wrote, read through OpenImageIO.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <lightvol/core/float_buffer.h>
#include <lightvol/core/limits.h>
#include <lightvol/core/result.h>

namespace lightvol {

// One channel of depths, row-major, first stored row first (docs/design.md §2: the top of the
// light's view unless flip_y). Values are as stored; their meaning is the light's `depth` encoding.
struct DepthImage {
  int width = 0;
  int height = 0;
  FloatBuffer values;  // width × height: heap memory, or the pages lightvol-image decoded into

  float at(int col, int row) const {
    return values[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) + col];
  }
};

struct DepthReadOptions {
  // Channel to read from a multi-channel image ("Z", "R", ...). Empty: the only channel, else a
  // channel named Z, depth or Y, else the only non-alpha channel; anything else is ambiguous.
  std::string channel;
  // How many images of this size the caller will read and build from (an omni light: 6): the
  // memory a build would need is checked against memory_budget() (core/limits.h) right after the
  // header is read, before any pixel is allocated.
  int images = 1;
  // What the caller will do with them, for that estimate (core/limits.h build_memory_bytes); the
  // default is the most demanding build.
  BuildMemory memory = BuildMemory::static_checked;
};

// Reads the first subimage of an EXR, TIFF, PNG, PFM, PGM, HDR or ZFile image (chosen by its
// first bytes, else its extension) with one float or 16-bit channel: 16-bit integers become
// [0, 1], as a depth buffer stores them. Other formats are refused unopened.
// Errors name the file: unreadable or truncated data, 8-bit or unknown channels, fewer than 2×2
// texels, and the first NaN, infinite or negative depth, by pixel (column, row as stored).
Result<DepthImage> read_depth_image(const std::string& path, const DepthReadOptions& options = {});

// The width and height of the image at `path` as its header gives them, read by lightvol itself
// without decoding anything (EXR files only, for now); nothing when it cannot tell. A hint for
// work that can start before the image is read (the static build's buffers), never a check:
// read_depth_image's own header decides.
std::optional<std::array<int, 2>> peek_image_size(const std::string& path);

// Writes a single-channel float image (EXR, TIFF, PFM; 16-bit for PNG), atomically.
Status write_depth_image(const std::string& path, const DepthImage& image);

// The first NaN, infinite or negative value, as an Error naming `source` and the pixel.
Status validate_depths(const DepthImage& image, const std::string& source);

}  // namespace lightvol

// Reading one channel of an image that holds other values than depths (a reference render)
// through the depth stage's checked, isolated image reader.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <lightvol/core/float_buffer.h>
#include <lightvol/core/result.h>

namespace lightvol {

// One channel of an image as floats, rows as stored.
struct ImageChannel {
  int width = 0;
  int height = 0;
  FloatBuffer values;  // width × height
};

struct ChannelReadOptions {
  // What the caller will hold per texel, checked against memory_budget() (core/limits.h) right
  // after the header is read, before any pixel is allocated ("a WxH image").
  std::uint64_t bytes_per_texel = sizeof(float);
  // When not empty, an image stored in 8 bits is refused as "<path>: <refuse_8_bit>".
  std::string refuse_8_bit;
};

// Reads the first channel of an image (a reference render, not depths) as floats, through
// read_depth_image's checked path: the same formats and checks of the file and its header, and
// OpenImageIO in a child process. The values are not validated. Errors name the file; a pixel
// read that fails is "<path>: cannot read image: <OpenImageIO's message>".
Result<ImageChannel> read_first_channel(const std::string& path,
                                        const ChannelReadOptions& options = {});

}  // namespace lightvol

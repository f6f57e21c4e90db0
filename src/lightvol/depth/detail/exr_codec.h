// lightvol-exr's side of reading images: plain EXR depth maps decoded with OpenEXR's C core
// (OpenEXRCore) alone, so that the program that serves them loads a few libraries instead of
// OpenImageIO's hundreds. It speaks lightvol-image's read conversation (image_codec.h) and gives
// the same header and the same floats OpenImageIO gives, for the files it takes: one part, not
// deep, scanlines or one level of tiles, exactly one channel of HALF or FLOAT sampled 1x1, not
// named as alpha, the data window the display window at (0, 0), and none of image_codec.cpp's
// header checks failing. Every other file, and any error while reading, it refuses at once (its
// message is never shown: the parent then reads the file through lightvol-image, whose answer,
// error or image, is the one it keeps). Linked only into lightvol-exr and the fuzz targets.
#pragma once

#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/detail/isolated.h>

namespace lightvol::detail {

// Answers one request on `channel` with `threads` decoding threads (0: every core); false when no
// request came (the channel closed) or it was not a read.
bool serve_exr_request(ChildOutput& channel, int threads);
// The same for a request whose first byte was read already.
bool serve_exr_request(ChildOutput& channel, int threads, ImageRequest request);

}  // namespace lightvol::detail

// lightvol-image's side of reading and writing images: OpenImageIO's open, the checks of the
// header it reads, the pixels; and the writers. Linked only into lightvol-image (and the fuzz
// targets, which serve images in process: core/detail/image_helper.h).
#pragma once

#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/detail/isolated.h>

namespace lightvol::detail {

// Answers one request (core/detail/image_helper.h ImageRequest) on `channel`, decoding with
// `threads` threads (0: every core); false when no request came (the channel closed) or it was
// not one.
//
// A read is a conversation, each step refusing before the next allocates: the parent sends the
// path, OpenImageIO's plugin name and the read-failure wording; the server opens the file with
// that plugin and answers with a verdict (fewer than 2x2 texels and volume images refused) and
// the header; the parent answers whether the header fits its memory budget; the server checks
// the header against the file (more than 2^30 texels; a header promising more decoded bytes than
// the file can hold: PFM exactly, EXR by its chunk table, any format by the most a compression
// packs into a byte; a data window other than the display window) and gives a second verdict; the
// parent names the channel to read (or -1); the server reads it as floats and answers with a last
// verdict and the pixels.
bool serve_image_request(ChildOutput& channel, int threads);
// The same for a request whose first byte was read already (lightvol-image's loop, which also
// serves ImageRequest::vdb); false for one that is not an image request.
bool serve_image_request(ChildOutput& channel, int threads, ImageRequest request);

}  // namespace lightvol::detail

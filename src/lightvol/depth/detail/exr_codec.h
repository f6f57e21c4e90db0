// lightvol-exr's side of reading images: plain EXR depth maps decoded with OpenEXR's C core
// (OpenEXRCore) alone, its ZIP chunks inflated by libdeflate when built with it, so that the
// program that serves them loads a few libraries instead of OpenImageIO's hundreds. It speaks
// lightvol-image's read conversation (image_codec.h) and gives the same header and the same floats
// OpenImageIO gives, for the files it takes: one part, not deep, scanlines or one level of tiles,
// exactly one channel of HALF or FLOAT sampled 1x1, not named as alpha, the data window the display
// window at (0, 0), and none of image_codec.cpp's header checks failing. Every other file, and any
// error while reading, it refuses at once (its message is never shown: the parent then reads the
// file through lightvol-image, whose answer, error or image, is the one it keeps). Linked only into
// lightvol-exr and the fuzz targets.
#pragma once

#include <cstddef>

#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/detail/isolated.h>

namespace lightvol::detail {

// Answers one request on `channel` with `threads` decoding threads (0: every core); false when no
// request came (the channel closed) or it was not a read.
bool serve_exr_request(ChildOutput& channel, int threads);
// The same for a request whose first byte was read already.
bool serve_exr_request(ChildOutput& channel, int threads, ImageRequest request);

// Whether ZIP and ZIPS chunks are inflated by libdeflate (lightvol-exr was built with it; CMake
// finds it when installed) rather than by OpenEXRCore's own routine, which uses zlib.
bool exr_zip_by_libdeflate();

// Undoes the ZIP (and ZIPS) compression of one chunk as OpenEXRCore 3.1's routine does
// (internal_zip.c): `packed` (a zlib stream) inflated to exactly `unpacked_size` bytes, the
// predictor undone (each byte plus the one before it, less 128), and the two halves interleaved
// (first half at even offsets) into `out`; a chunk whose packed size is its unpacked size is stored
// as is. False on any error (not a zlib stream, another size), as that routine fails; false too for
// an empty chunk, whose bytes that routine leaves unwritten; and always without libdeflate. Exposed
// for the tests.
bool undo_exr_zip(const void* packed, std::size_t packed_size, void* out,
                  std::size_t unpacked_size);

}  // namespace lightvol::detail

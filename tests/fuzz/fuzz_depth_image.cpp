// Fuzz target: the depth-image loading path (OpenImageIO + our channel and value checks). The
// first byte picks the extension the bytes are read as; the rest is the file.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <lightvol/core/check.h>
#include <lightvol/core/detail/image_helper.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/depth/detail/exr_codec.h>
#include <lightvol/depth/detail/image_codec.h>

#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The decoders in forked children of this process (their coverage counts), not lightvol-image
  // and lightvol-exr: an EXR goes to lightvol-exr's first, then (declined) to OpenImageIO's.
  static const bool in_process =
      (lightvol::detail::set_in_process_image_server(&lightvol::detail::serve_image_request),
       lightvol::detail::set_in_process_exr_server(&lightvol::detail::serve_exr_request), true);
  (void)in_process;
  if (size < 1) return 0;
  // The formats read_depth_image reads, then three it refuses without opening.
  static const char* const kExtensions[] = {".exr",   ".png", ".tif", ".pfm", ".hdr",
                                            ".zfile", ".pgm", ".dpx", ".jpg", ".bmp"};
  constexpr std::size_t kCount = sizeof kExtensions / sizeof kExtensions[0];
  const lightvol::fuzz::TempInput file(data + 1, size - 1, kExtensions[data[0] % kCount]);
  const lightvol::Result<lightvol::DepthImage> image = lightvol::read_depth_image(file.path());
  if (!image) {
    LV_CHECK(image.error().message.rfind(file.path(), 0) == 0);
    return 0;
  }
  LV_CHECK(image->width >= 2 && image->height >= 2);
  LV_CHECK_EQ(image->values.size(),
              static_cast<std::size_t>(image->width) * static_cast<std::size_t>(image->height));
  for (const float v : image->values) LV_CHECK(std::isfinite(v) && v >= 0);
  return 0;
}

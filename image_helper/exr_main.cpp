// lightvol-exr: reads plain EXR depth maps for the lightvol library (depth/detail/exr_codec.h),
// answering read requests one after another on file descriptor 3, as lightvol-image does, until it
// closes. It links OpenEXR's C core (and libdeflate) and not OpenImageIO or OpenVDB: it starts in
// a fraction of lightvol-image's time. Every file that is not plain it declines, and the library reads it
// through lightvol-image. Not meant to be run by hand.
#include <malloc.h>

#include <cstdio>
#include <cstring>
#include <new>

#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/detail/isolated.h>
#include <lightvol/depth/detail/exr_codec.h>

int main(int argc, char** argv) {
  if (argc > 1) {
    std::fprintf(stderr,
                 "lightvol-exr: the lightvol library's reader of plain EXR depth maps; it takes no "
                 "arguments and answers requests on file descriptor %d\n",
                 lightvol::kProgramChannel);
    return std::strcmp(argv[1], "--help") == 0 ? 0 : 2;
  }
  // As in lightvol-image (main.cpp): freed chunk buffers are reused rather than unmapped.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
  lightvol::ChildOutput channel(lightvol::kProgramChannel);
  try {
    channel.write_value(lightvol::kProgramReady);
    while (lightvol::detail::serve_exr_request(channel, 0))
      channel.write_value(lightvol::kProgramReady);
  } catch (const std::bad_alloc&) {
    return lightvol::kChildOutOfMemory;
  } catch (...) {
    return lightvol::kChildThrew;
  }
  return 0;
}

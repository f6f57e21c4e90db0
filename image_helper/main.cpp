// lightvol-image: decodes and encodes images, and reads OpenVDB density grids, for the lightvol
// library, answering requests one after another on file descriptor 3 (core/detail/isolated.h
// IsolatedServer; the requests are core/detail/image_helper.h's, the answers
// depth/detail/image_codec.h's and airlight/detail/vdb_codec.h's) until it closes. The only program
// of lightvol that links OpenImageIO and OpenVDB; not meant to be run by hand.
#include <malloc.h>

#include <cstdio>
#include <cstring>
#include <new>

#include <lightvol/airlight/detail/vdb_codec.h>
#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/detail/isolated.h>
#include <lightvol/depth/detail/image_codec.h>

int main(int argc, char** argv) {
  if (argc > 1) {
    std::fprintf(stderr,
                 "lightvol-image: the lightvol library's image decoder; it takes no arguments and "
                 "answers requests on file descriptor %d\n",
                 lightvol::kProgramChannel);
    return std::strcmp(argv[1], "--help") == 0 ? 0 : 2;
  }
  // Each request decodes into buffers of a few hundred KiB to tens of MiB (OpenEXR's chunks and
  // line buffers, the converted rows), freed and allocated again request after request and chunk
  // after chunk. Past glibc's mmap threshold each such block is a fresh mapping, zeroed by the
  // kernel page by page on first touch, then unmapped on free; the next one faults in anew (tens of
  // thousands of page faults for one 4097² map). Serving blocks below 32 MiB from the heap, and
  // keeping up to 64 MiB of freed heap instead of trimming it, lets the next buffer reuse the pages
  // of the last one.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
  lightvol::ChildOutput channel(lightvol::kProgramChannel);
  try {
    // Loaded, or done with a request: the parent sets the limits for the next one now.
    channel.write_value(lightvol::kProgramReady);
    using lightvol::detail::ImageRequest;
    ImageRequest request{};
    while (channel.read_value(&request) &&
           (request == ImageRequest::vdb
                ? lightvol::detail::serve_vdb_request(channel)
                : lightvol::detail::serve_image_request(channel, 0, request)))
      channel.write_value(lightvol::kProgramReady);
  } catch (const std::bad_alloc&) {
    return lightvol::kChildOutOfMemory;
  } catch (...) {
    return lightvol::kChildThrew;
  }
  return 0;
}

// The main loop the reader programs share (lightvol-image: image_helper/main.cpp; lightvol-exr:
// image_helper/exr_main.cpp). Include it only from a program's main.
#pragma once

#include <malloc.h>

#include <cstdio>
#include <cstring>
#include <new>

#include <lightvol/core/detail/isolated.h>

namespace lightvol::detail {

// Answers any argument with `what` and the channel (exit 0 for --help, 2 otherwise). Then serves
// requests on kProgramChannel: kProgramReady once loaded and after each request that serve(channel)
// answered, until serve returns false (the parent closed the channel, or sent what the program does
// not serve). Out of memory and any other exception end it with the exit codes the parent reads.
//
// Each request decodes into buffers of a few hundred KiB to tens of MiB (chunk and line buffers,
// converted rows), freed and allocated again request after request and chunk after chunk. Past
// glibc's mmap threshold each such block is a fresh mapping, zeroed by the kernel page by page on
// first touch, then unmapped on free (tens of thousands of page faults for one 4097² map). Serving
// blocks below 32 MiB from the heap, and keeping up to 64 MiB of freed heap instead of trimming it,
// lets the next buffer reuse the pages of the last one.
template <class Serve>
int run_reader_program(int argc, char** argv, const char* what, Serve serve) {
  if (argc > 1) {
    std::fprintf(stderr, "%s; it takes no arguments and answers requests on file descriptor %d\n",
                 what, kProgramChannel);
    return std::strcmp(argv[1], "--help") == 0 ? 0 : 2;
  }
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
  ChildOutput channel(kProgramChannel);
  try {
    // Loaded, or done with a request: the parent sets the limits for the next one now.
    channel.write_value(kProgramReady);
    while (serve(channel)) channel.write_value(kProgramReady);
  } catch (const std::bad_alloc&) {
    return kChildOutOfMemory;
  } catch (...) {
    return kChildThrew;
  }
  return 0;
}

}  // namespace lightvol::detail

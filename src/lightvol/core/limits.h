// Resource limits, decided before work starts: a memory budget that inputs are measured against
// as soon as their headers say how big they are (image dimensions, mesh element counts, shadow-map
// sizes), so a forged or absurd header is refused with a message instead of an allocation.
#pragma once

#include <cstdint>
#include <string>

#include <lightvol/core/result.h>

namespace lightvol {

// Physical memory of the machine (sysconf), 0 if unknown.
std::uint64_t physical_memory_bytes();

// 75% of physical memory (16 GiB if unknown): the budget when nothing else is set.
std::uint64_t default_memory_budget();

// The process-wide budget every reader checks against (set_memory_budget; a command line sets it
// from a flag).
std::uint64_t memory_budget();
void set_memory_budget(std::uint64_t bytes);

// "512M", "8G", "1.5GiB", "2000000000": bytes. The number is decimal digits with at most one '.';
// the suffix, if any, is exactly "B", or K M G T (powers of 1024, either case) alone or followed
// by exactly "B" or "iB" ("1Gb", "1GIB", "0x10" and " 8G" are refused). The Error ("'<text>' is not
// a memory size (examples: ...)") quotes the text; a caller that took it from a flag prefixes the
// flag.
Result<std::uint64_t> parse_memory_size(const std::string& text);

// "1.5 GiB", for messages.
std::string format_bytes(std::uint64_t bytes);

// What a command does with W×H depth maps, for its memory estimate (build_memory_bytes).
enum class BuildMemory {
  static_checked,    // build: the static volume, checked before it is written (the default)
  static_unchecked,  // build --no-check: the static volume held whole, then written
  static_streamed,   // build --no-check to PLY: the static volume's rows streamed to the writer
  adaptive,          // build --adaptive: texel depths, the error pyramid, the (small) mesh
  stats,             // stats: the error pyramid and the adaptive meshes at each bound
};

// Peak memory (resident, of the largest process) of a build from `images` depth images of W×H
// texels in `mode`: lightvol's fixed part plus, per texel, what that mode allocates, or
// lightvol-image's, which decodes each image, whichever is larger (docs/robustness.md lists the
// terms). Meant to be at or above the measured peak and within
// 1.25× of it (tests/cli/memory_estimate_test.cpp).
std::uint64_t build_memory_bytes(BuildMemory mode, std::int64_t width, std::int64_t height,
                                 int images = 1);

// Peak memory of an adaptive build (build --adaptive) from `images` maps of W×H texels once their
// quadtree tessellation is known to have `quadtree_triangles` triangles in all: the per-texel
// tables, then what grows with the triangles (the quadtree grid, the collapse's tables when
// `collapse`, the volume assembled from the grid, its check and its writer), or lightvol-image's
// peak, whichever is larger. The adaptive builders check it against the budget before they
// collapse and assemble; build_memory_bytes(BuildMemory::adaptive) covers what they allocate
// before that, a grid of up to one vertex and two triangles per texel included. At or above the
// measured peak and within 1.25× of it, for any map up to the worst case, noise at a bound of 0
// (every texel a vertex; tests/cli/memory_estimate_test.cpp). `float_depths`: every image's texel
// depths are held as floats (TexelDepths::float_depths), 4 bytes a texel less.
std::uint64_t adaptive_memory_bytes(std::int64_t width, std::int64_t height, int images,
                                    std::uint64_t quadtree_triangles, bool collapse,
                                    bool float_depths = false);

// The per-texel terms of build_memory_bytes, for the docs and tests.
double build_bytes_per_texel(BuildMemory mode);
// lightvol's fixed part: its resident size before it reads a map, and a build's fixed buffers.
std::uint64_t process_base_bytes();

// Peak memory of rendering a W×H shadow map `faces` times (double window depths, encoded floats,
// GPU readback).
std::uint64_t shadow_map_memory_bytes(std::int64_t width, std::int64_t height, int faces = 1);

// An Error "<source>: <what> needs about X of memory, more than the budget Y; raise it with
// set_memory_budget() (e.g. to ZG)" when `needed` exceeds memory_budget(), else success.
Status check_memory(std::uint64_t needed, const std::string& source, const std::string& what);

}  // namespace lightvol

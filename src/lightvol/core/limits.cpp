#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string_view>

#include <lightvol/core/limits.h>
#include <lightvol/core/text.h>

namespace lightvol {
namespace {
std::atomic<std::uint64_t> g_budget{0};  // 0: not set, use the default
}  // namespace

std::uint64_t physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page_size = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page_size <= 0) return 0;
  return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size);
}

std::uint64_t default_memory_budget() {
  const std::uint64_t physical = physical_memory_bytes();
  if (physical == 0) return std::uint64_t{16} << 30;
  return physical / 4 * 3;
}

std::uint64_t memory_budget() {
  const std::uint64_t b = g_budget.load(std::memory_order_relaxed);
  return b != 0 ? b : default_memory_budget();
}

void set_memory_budget(std::uint64_t bytes) { g_budget.store(bytes, std::memory_order_relaxed); }

Result<std::uint64_t> parse_memory_size(const std::string& text) {
  const Error bad{"'" + text + "' is not a memory size (examples: 512M, 8G, 1.5GiB, 2000000000)"};
  // The number: decimal digits with at most one '.' (core/text.h parse_decimal, without a sign
  // or an exponent); then the suffix, exactly one of those docs/robustness.md lists.
  std::size_t i = 0;
  while (i < text.size() && ((text[i] >= '0' && text[i] <= '9') || text[i] == '.')) ++i;
  const std::optional<double> value = parse_decimal(std::string_view(text).substr(0, i));
  if (!value) return bad;
  const std::string suffix = text.substr(i);
  double scale = 1;
  if (!suffix.empty() && suffix != "B") {
    // K, M, G or T in either case (powers of 1024), alone or followed by exactly "B" or "iB":
    // "1Gb" (b is bits), "1GIB" and "1GBytes" are refused.
    const std::string rest = suffix.substr(1);
    if (rest != "" && rest != "B" && rest != "iB") return bad;
    switch (std::toupper(static_cast<unsigned char>(suffix[0]))) {
      case 'K':
        scale = 1024.0;
        break;
      case 'M':
        scale = 1024.0 * 1024;
        break;
      case 'G':
        scale = 1024.0 * 1024 * 1024;
        break;
      case 'T':
        scale = 1024.0 * 1024 * 1024 * 1024;
        break;
      default:
        return bad;
    }
  }
  const double bytes = *value * scale;
  if (!std::isfinite(bytes) || bytes < 1 || bytes > 1.8e19) return bad;
  return static_cast<std::uint64_t>(bytes);
}

std::string format_bytes(std::uint64_t bytes) {
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024 && u < 6) {
    v /= 1024;
    ++u;
  }
  char buffer[64];
  if (u == 0)
    std::snprintf(buffer, sizeof buffer, "%llu bytes", static_cast<unsigned long long>(bytes));
  else
    std::snprintf(buffer, sizeof buffer, "%.1f %s", v, units[u]);
  return buffer;
}

namespace {
// Measured peaks (2048² spot, 6 × 1024² omni; tests/cli/memory_estimate_test.cpp): lightvol itself
// holds checked static 39.8 bytes per texel (the check adds a few MiB of scratch to the volume it
// checks), --no-check static held 38.6–39, streamed 4.05,
// adaptive and stats 25.2 (21 at 16384²), over its own few MiB; lightvol-image, which decodes the
// images (one at a time), reaches 130 MiB (its libraries) plus about 6.3 bytes per texel.

// The check's scratch per triangle of a static volume: its edge uses are bucketed a cache-sized
// chunk at a time, so it needs about 1.4 MiB per thread plus 12 bytes per 1024 faces (0.1 byte
// per triangle; docs/checks.md), rounded up. A static volume has about two triangles per texel.
constexpr double kCheckBytesPerTriangle = 0.5;
// A static volume held whole: 12 bytes of position per vertex (one per texel) and 12 bytes of
// indices per triangle (two per texel).
constexpr double kStaticMeshBytesPerTexel = 12 + 2 * 12;
// The depth floats as received from lightvol-image.
constexpr double kDepthBytesPerTexel = 4;
// Adaptive: the floats read, the texel depths (doubles, or floats when exact: 4 bytes less) and
// error scales (doubles), the error pyramid (floats, a third of a texel's), the quadtree's and the
// collapse's per-texel tables.
constexpr double kAdaptiveBytesPerTexel = 24;
// Adaptive, before the tessellation's size is known: its grid may hold every texel as a vertex
// (4 bytes) and two triangles per texel (12 bytes each), as it does on noise at a bound of 0.
constexpr double kAdaptiveGridWorstBytesPerTexel = 4 + 2 * 12;
// Adaptive, once the quadtree's triangle count T is known, per quadtree triangle: the quadtree
// grid (a vertex id per two triangles, three indices) and the volume assembled from it (12 bytes
// of position per two triangles, 12 of indices, the check's and the writer's share); the collapse
// adds its tables (a point and a star of triangles per vertex, a triangle's corners and flags) and
// the grid it returns (the collapse rewrites the quadtree grid's own indices). Measured on noise at
// a bound of 0 (T = 2 per texel; 2048²: peaks of 400.5 MiB and 500.7 MiB, 36.5 and 49 bytes per
// triangle over the per-texel tables), with some room above.
constexpr double kQuadtreeBytesPerTriangle = 40;
constexpr double kCollapseBytesPerTriangle = 57;
// An omni light's collapse keeps each face's quadtree grid for its seam rounds and collapses a copy
// of its indices (omni_adaptive.cpp): 12 bytes more per triangle.
constexpr double kOmniCollapseBytesPerTriangle = kCollapseBytesPerTriangle + 12;
// lightvol-image: its libraries (OpenImageIO and what it loads), then the decoded image and the
// file's buffers. lightvol-exr, which reads plain EXR files first, is far smaller (a few MiB of
// libraries), but any file it declines is read by lightvol-image, so the estimate is
// lightvol-image's.
constexpr double kImageReaderBase = 136.0 * (1 << 20);
constexpr double kImageReaderBytesPerTexel = 7;
}  // namespace

double build_bytes_per_texel(BuildMemory mode) {
  switch (mode) {
    case BuildMemory::static_checked:
      // + the writer's buffers + the check's scratch
      return kDepthBytesPerTexel + kStaticMeshBytesPerTexel + 2 + 2 * kCheckBytesPerTriangle;
    case BuildMemory::static_unchecked:
      return kDepthBytesPerTexel + kStaticMeshBytesPerTexel + 2;  // + the writer's buffers
    case BuildMemory::static_streamed:
      return kDepthBytesPerTexel + 0.5;  // the rows in flight are a fixed few MiB
    case BuildMemory::adaptive:
      return kAdaptiveBytesPerTexel + kAdaptiveGridWorstBytesPerTexel;
    case BuildMemory::stats:
      return kAdaptiveBytesPerTexel;
  }
  return 0;
}

// lightvol's resident size before it reads a map, and the fixed working buffers of a build.
std::uint64_t process_base_bytes() { return std::uint64_t{12} << 20; }

std::uint64_t build_memory_bytes(BuildMemory mode, std::int64_t width, std::int64_t height,
                                 int images) {
  if (width <= 0 || height <= 0 || images <= 0) return 0;
  const double texels = static_cast<double>(width) * static_cast<double>(height);
  // The peak is that of lightvol or of lightvol-image (a process of its own, one image at a time),
  // whichever is larger.
  const double lightvol = static_cast<double>(process_base_bytes()) +
                          texels * static_cast<double>(images) * build_bytes_per_texel(mode);
  const double reader = kImageReaderBase + texels * kImageReaderBytesPerTexel;
  const double bytes = std::max(lightvol, reader);
  return bytes >= 1.8e19 ? std::uint64_t{1} << 63 : static_cast<std::uint64_t>(bytes);
}

std::uint64_t adaptive_memory_bytes(std::int64_t width, std::int64_t height, int images,
                                    std::uint64_t quadtree_triangles, bool collapse,
                                    bool float_depths) {
  if (width <= 0 || height <= 0 || images <= 0) return 0;
  const double texels = static_cast<double>(width) * static_cast<double>(height);
  const double per_texel = kAdaptiveBytesPerTexel - (float_depths ? 4 : 0);
  const double lightvol =
      static_cast<double>(process_base_bytes()) + texels * static_cast<double>(images) * per_texel +
      static_cast<double>(quadtree_triangles) * (!collapse    ? kQuadtreeBytesPerTriangle
                                                 : images > 1 ? kOmniCollapseBytesPerTriangle
                                                              : kCollapseBytesPerTriangle);
  const double reader = kImageReaderBase + texels * kImageReaderBytesPerTexel;
  const double bytes = std::max(lightvol, reader);
  return bytes >= 1.8e19 ? std::uint64_t{1} << 63 : static_cast<std::uint64_t>(bytes);
}

std::uint64_t shadow_map_memory_bytes(std::int64_t width, std::int64_t height, int faces) {
  if (width <= 0 || height <= 0 || faces <= 0) return 0;
  // Per texel and face: 8 (double window depth) + 4 (encoded float) + 4 (GPU readback) + 4
  // (depth attachment).
  constexpr double kBytesPerTexel = 20;
  const double bytes = static_cast<double>(width) * static_cast<double>(height) *
                       static_cast<double>(faces) * kBytesPerTexel;
  return bytes >= 1.8e19 ? std::uint64_t{1} << 63 : static_cast<std::uint64_t>(bytes);
}

Status check_memory(std::uint64_t needed, const std::string& source, const std::string& what) {
  const std::uint64_t budget = memory_budget();
  if (needed <= budget) return {};
  // Suggest a round number of GiB above the need.
  const std::uint64_t gib = (needed >> 30) + 1;
  return Error{source + ": " + what + " needs about " + format_bytes(needed) +
               " of memory, more than the budget of " + format_bytes(budget) +
               "; raise it with set_memory_budget() (e.g. to " + std::to_string(gib) + "G)"};
}

}  // namespace lightvol

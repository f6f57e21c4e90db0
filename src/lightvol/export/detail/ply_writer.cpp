#include <bit>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <lightvol/core/check.h>
#include <lightvol/export/detail/ply_writer.h>

namespace lightvol::detail {

static_assert(std::endian::native == std::endian::little,
              "binary PLY output assumes little-endian");

namespace {

std::string header(std::uint64_t vertices, std::uint64_t triangles, bool ascii) {
  return std::string("ply\nformat ") + (ascii ? "ascii" : "binary_little_endian") +
         " 1.0\ncomment lightvol light volume\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(triangles) + "\nproperty list uchar int vertex_indices\nend_header\n";
}

// Appends text to a block buffer and flushes it when full.
class BlockWriter {
 public:
  explicit BlockWriter(std::FILE* f) : f_(f) { buf_.reserve(kBlock + 256); }
  char* reserve(std::size_t n) {
    if (buf_.size() + n > kBlock) flush();
    const std::size_t at = buf_.size();
    buf_.resize(at + n);
    return buf_.data() + at;
  }
  void shrink_to(char* end) { buf_.resize(static_cast<std::size_t>(end - buf_.data())); }
  bool flush() {
    ok_ = ok_ && std::fwrite(buf_.data(), 1, buf_.size(), f_) == buf_.size();
    buf_.clear();
    return ok_;
  }

 private:
  static constexpr std::size_t kBlock = 1 << 22;
  std::FILE* f_;
  std::vector<char> buf_;
  bool ok_ = true;
};

}  // namespace

Status write_ply(std::FILE* file, MeshStream& mesh, bool ascii, bool* write_failed) {
  *write_failed = false;
  const std::string head = header(mesh.num_vertices(), mesh.num_triangles(), ascii);
  if (std::fwrite(head.data(), 1, head.size(), file) != head.size()) {
    *write_failed = true;
    return {};
  }
  std::uint64_t vertices = 0, triangles = 0;

  if (!ascii) {
    // Positions are already little-endian float triples.
    Status s = mesh.positions([&](const float* xyz, std::size_t n) {
      vertices += n;
      *write_failed = std::fwrite(xyz, 3 * sizeof(float), n, file) != n;
      return !*write_failed;
    });
    if (!s || *write_failed) return s;
    constexpr std::size_t kFaces = 1 << 16;
    std::vector<unsigned char> block(13 * kFaces);
    s = mesh.triangles([&](const std::uint32_t* abc, std::size_t count) {
      triangles += count;
      for (std::size_t t0 = 0; t0 < count; t0 += kFaces) {
        const std::size_t n = std::min(kFaces, count - t0);
        unsigned char* out = block.data();
        for (std::size_t t = t0; t < t0 + n; ++t) {
          *out++ = 3;
          std::memcpy(out, &abc[3 * t], 12);
          out += 12;
        }
        if (std::fwrite(block.data(), 13, n, file) != n) {
          *write_failed = true;
          return false;
        }
      }
      return true;
    });
    if (!s || *write_failed) return s;
    LV_CHECK_EQ(vertices, mesh.num_vertices());
    LV_CHECK_EQ(triangles, mesh.num_triangles());
    return {};
  }

  // ASCII: shortest round-trip decimal for every float.
  BlockWriter out(file);
  Status s = mesh.positions([&](const float* xyz, std::size_t n) {
    vertices += n;
    for (std::size_t v = 0; v < n; ++v) {
      char* p = out.reserve(3 * 24 + 1);
      char* const start = p;
      for (int k = 0; k < 3; ++k) {
        p = std::to_chars(p, start + 3 * 24, xyz[3 * v + k]).ptr;
        *p++ = k < 2 ? ' ' : '\n';
      }
      out.shrink_to(p);
    }
    return true;
  });
  if (!s) return s;
  s = mesh.triangles([&](const std::uint32_t* abc, std::size_t n) {
    triangles += n;
    for (std::size_t t = 0; t < n; ++t) {
      char* p = out.reserve(2 + 3 * 11 + 1);
      char* const start = p;
      *p++ = '3';
      for (int k = 0; k < 3; ++k) {
        *p++ = ' ';
        p = std::to_chars(p, start + 40, abc[3 * t + k]).ptr;
      }
      *p++ = '\n';
      out.shrink_to(p);
    }
    return true;
  });
  if (!s) return s;
  *write_failed = !out.flush();
  LV_CHECK_EQ(vertices, mesh.num_vertices());
  LV_CHECK_EQ(triangles, mesh.num_triangles());
  return {};
}

}  // namespace lightvol::detail

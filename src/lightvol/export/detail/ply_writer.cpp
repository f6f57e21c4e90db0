#include <bit>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <lightvol/export/detail/ply_writer.h>

namespace lightvol::detail {

static_assert(std::endian::native == std::endian::little,
              "binary PLY output assumes little-endian");

namespace {

std::string header(const Mesh& mesh, bool ascii) {
  return std::string("ply\nformat ") + (ascii ? "ascii" : "binary_little_endian") +
         " 1.0\ncomment lightvol light volume\nelement vertex " +
         std::to_string(mesh.num_vertices()) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(mesh.num_triangles()) +
         "\nproperty list uchar int vertex_indices\nend_header\n";
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

bool write_ply(std::FILE* file, const Mesh& mesh, bool ascii) {
  const std::string head = header(mesh, ascii);
  if (std::fwrite(head.data(), 1, head.size(), file) != head.size()) return false;
  const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();

  if (!ascii) {
    // Positions are already little-endian float triples.
    if (std::fwrite(mesh.positions.data(), sizeof(float), 3 * nv, file) != 3 * nv) return false;
    constexpr std::size_t kFaces = 1 << 16;
    std::vector<unsigned char> block(13 * kFaces);
    for (std::size_t t0 = 0; t0 < nt; t0 += kFaces) {
      const std::size_t n = std::min(kFaces, nt - t0);
      unsigned char* out = block.data();
      for (std::size_t t = t0; t < t0 + n; ++t) {
        *out++ = 3;
        std::memcpy(out, &mesh.indices[3 * t], 12);
        out += 12;
      }
      if (std::fwrite(block.data(), 13, n, file) != n) return false;
    }
    return true;
  }

  // ASCII: shortest round-trip decimal for every float.
  BlockWriter out(file);
  for (std::size_t v = 0; v < nv; ++v) {
    char* p = out.reserve(3 * 24 + 1);
    char* const start = p;
    for (int k = 0; k < 3; ++k) {
      p = std::to_chars(p, start + 3 * 24, mesh.positions[3 * v + k]).ptr;
      *p++ = k < 2 ? ' ' : '\n';
    }
    out.shrink_to(p);
  }
  for (std::size_t t = 0; t < nt; ++t) {
    char* p = out.reserve(2 + 3 * 11 + 1);
    char* const start = p;
    *p++ = '3';
    for (int k = 0; k < 3; ++k) {
      *p++ = ' ';
      p = std::to_chars(p, start + 40, mesh.indices[3 * t + k]).ptr;
    }
    *p++ = '\n';
    out.shrink_to(p);
  }
  return out.flush();
}

}  // namespace lightvol::detail

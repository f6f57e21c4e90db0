#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <string_view>
#include <vector>

#include <lightvol/core/text.h>
#include <lightvol/io/detail/obj_reader.h>
#include <lightvol/io/detail/text_numbers.h>

namespace lightvol::detail {
namespace {

// The next blank-separated word of `line` from `*at`, or an empty view at its end.
std::string_view next_word(std::string_view line, std::size_t* at) {
  const std::size_t start = line.find_first_not_of(" \t\r", *at);
  if (start == std::string_view::npos) {
    *at = line.size();
    return {};
  }
  const std::size_t end = std::min(line.find_first_of(" \t\r", start), line.size());
  *at = end;
  return line.substr(start, end - start);
}

// The vertex number of a face vertex v, v/t, v//n or v/t/n (t and n are checked, then dropped).
bool parse_face_vertex(std::string_view word, long long* vertex) {
  const char* p = word.data();
  const char* const end = p + word.size();
  const auto integer = [&](long long* out) {
    const auto [next, ec] = std::from_chars(p, end, *out);
    if (ec != std::errc()) return false;
    p = next;
    return true;
  };
  long long ignored = 0;
  if (!integer(vertex)) return false;
  if (p == end) return true;  // v
  if (*p++ != '/') return false;
  if (p != end && *p != '/' && !integer(&ignored)) return false;  // v/t
  if (p == end) return true;
  if (*p++ != '/') return false;
  return integer(&ignored) && p == end;  // v//n, v/t/n
}

}  // namespace

Result<Mesh> read_obj(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open: " + std::strerror(errno)};
  Mesh mesh;
  std::vector<long long> face;
  // Positive indices may name vertices defined further on; they are checked at the end.
  struct Forward {
    std::size_t number, line;
    long long vertex;
  };
  std::vector<Forward> forward;
  std::size_t faces = 0;
  std::string text;
  for (std::size_t number = 1; std::getline(in, text); ++number) {
    const auto fail = [&](const std::string& what) -> Result<Mesh> {
      return Error{path + ": OBJ line " + std::to_string(number) + ": " + what};
    };
    if (text.find('\0') != std::string::npos)
      return Error{path + ": not an OBJ file (binary data in a text format)"};
    std::string_view line(text);
    line = line.substr(0, line.find('#'));
    std::size_t at = 0;
    const std::string_view keyword = next_word(line, &at);
    if (keyword == "v") {
      float xyz[3];
      for (float& c : xyz) {
        const std::string_view word = next_word(line, &at);
        if (word.empty())
          return fail("expected a vertex 'v x y z', got '" + utf8_prefix(line, 60) + "'");
        if (!parse_coordinate(word, &c)) return fail(not_a_coordinate(word));
      }
      mesh.positions.insert(mesh.positions.end(), xyz, xyz + 3);
    } else if (keyword == "f") {
      face.clear();
      const auto so_far = static_cast<long long>(mesh.num_vertices());
      for (std::string_view word = next_word(line, &at); !word.empty();
           word = next_word(line, &at)) {
        long long v = 0;
        if (!parse_face_vertex(word, &v))
          return fail("face vertex '" + utf8_prefix(word, 40) + "' is not v, v/t, v//n or v/t/n");
        if (v == 0 || v < -so_far)
          return fail("face " + std::to_string(faces) + " names vertex " + std::to_string(v) +
                      ", but there are " + std::to_string(so_far) + " before it");
        if (v > so_far) forward.push_back({faces, number, v});
        face.push_back(v < 0 ? so_far + v : v - 1);
      }
      if (face.size() < 3)
        return fail("face " + std::to_string(faces) + " has " + std::to_string(face.size()) +
                    " vertices");
      for (std::size_t k = 1; k + 1 < face.size(); ++k)
        mesh.indices.insert(mesh.indices.end(), {static_cast<std::uint32_t>(face[0]),
                                                 static_cast<std::uint32_t>(face[k]),
                                                 static_cast<std::uint32_t>(face[k + 1])});
      ++faces;
    }
  }
  if (in.bad()) return Error{path + ": cannot read: " + std::strerror(errno)};
  for (const Forward& f : forward)
    if (static_cast<unsigned long long>(f.vertex) > mesh.num_vertices())
      return Error{path + ": OBJ line " + std::to_string(f.line) + ": face " +
                   std::to_string(f.number) + " names vertex " + std::to_string(f.vertex) +
                   ", but there are " + std::to_string(mesh.num_vertices())};
  return mesh;
}

}  // namespace lightvol::detail

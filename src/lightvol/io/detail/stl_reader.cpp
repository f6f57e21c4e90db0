#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <string_view>
#include <vector>

#include <lightvol/core/text.h>
#include <lightvol/io/detail/stl_reader.h>
#include <lightvol/io/detail/text_numbers.h>

namespace lightvol::detail {
namespace {

// The blank-separated words of a line.
std::vector<std::string_view> words_of(std::string_view line) {
  std::vector<std::string_view> words;
  for (std::size_t at = 0;;) {
    at = line.find_first_not_of(" \t\r\f\v", at);
    if (at == std::string_view::npos) return words;
    const std::size_t end = std::min(line.find_first_of(" \t\r\f\v", at), line.size());
    words.push_back(line.substr(at, end - at));
    at = end;
  }
}

bool is_keyword(std::string_view word, std::string_view keyword) {
  return word.size() == keyword.size() &&
         std::equal(word.begin(), word.end(), keyword.begin(), [](char a, char b) {
           return std::tolower(static_cast<unsigned char>(a)) == b;
         });
}

// Where the reader is in the file, and so which keyword it expects next.
enum class State { outside, solid, facet, loop, looped };

std::string_view expected(State state, int corners) {
  switch (state) {
    case State::outside:
      return "'solid'";
    case State::solid:
      return "'facet' or 'endsolid'";
    case State::facet:
      return "'outer loop'";
    case State::loop:
      return corners < 3 ? "'vertex'" : "'endloop'";
    case State::looped:
      return "'endfacet'";
  }
  return "";
}

}  // namespace

// Long (over 80 lines) on purpose: one pass over the lines, a case per keyword, each with its own
// message; the cases share the state, the line number and the facet being read.
Result<Mesh> read_stl_ascii(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open: " + std::strerror(errno)};
  Mesh mesh;
  State state = State::outside;
  int corners = 0;                   // of the facet being read
  std::array<float, 9> facet{};      // its corners' coordinates
  std::size_t facets = 0, line = 0;  // facets read; the current line
  std::string text;
  while (std::getline(in, text)) {
    ++line;
    const auto fail = [&](const std::string& what) -> Result<Mesh> {
      return Error{path + ": STL line " + std::to_string(line) + ": " + what};
    };
    if (text.find('\0') != std::string::npos)
      return Error{path + ": not an ASCII STL file (binary data in line " + std::to_string(line) +
                   ")"};
    const std::vector<std::string_view> words = words_of(text);
    if (words.empty()) continue;
    const std::string_view key = words[0];
    const auto unexpected = [&] {
      return fail("expected " + std::string(expected(state, corners)) + ", got '" +
                  utf8_prefix(key, 40) + "'");
    };
    if (is_keyword(key, "solid")) {
      if (state != State::outside) return unexpected();
      state = State::solid;
    } else if (is_keyword(key, "endsolid")) {
      if (state != State::solid) return unexpected();
      state = State::outside;
    } else if (is_keyword(key, "facet")) {
      if (state != State::solid) return unexpected();
      state = State::facet;
    } else if (is_keyword(key, "outer")) {
      if (state != State::facet) return unexpected();
      if (words.size() != 2 || !is_keyword(words[1], "loop")) return fail("expected 'outer loop'");
      state = State::loop;
      corners = 0;
    } else if (is_keyword(key, "vertex")) {
      if (state != State::loop || corners == 3) return unexpected();
      if (words.size() != 4) return fail("expected 'vertex x y z'");
      for (int k = 0; k < 3; ++k)
        if (!parse_coordinate(words[1 + k], &facet[3 * corners + k]))
          return fail(not_a_coordinate(words[1 + k]));
      ++corners;
    } else if (is_keyword(key, "endloop")) {
      if (state != State::loop || corners != 3) {
        if (state == State::loop)
          return fail("facet " + std::to_string(facets) + " has " + std::to_string(corners) +
                      " vertices, not 3");
        return unexpected();
      }
      state = State::looped;
    } else if (is_keyword(key, "endfacet")) {
      if (state != State::looped) return unexpected();
      state = State::solid;
      if (mesh.num_vertices() > std::numeric_limits<std::uint32_t>::max() - 3)
        return fail("more vertices than 32-bit indices hold");
      const auto first = static_cast<std::uint32_t>(mesh.num_vertices());
      mesh.positions.insert(mesh.positions.end(), facet.begin(), facet.end());
      const auto same = [&](int a, int b) {
        return facet[3 * a] == facet[3 * b] && facet[3 * a + 1] == facet[3 * b + 1] &&
               facet[3 * a + 2] == facet[3 * b + 2];
      };
      if (!same(0, 1) && !same(0, 2) && !same(1, 2))
        mesh.indices.insert(mesh.indices.end(), {first, first + 1, first + 2});
      ++facets;
    } else {
      return unexpected();
    }
  }
  if (in.bad()) return Error{path + ": cannot read: " + std::strerror(errno)};
  if (state != State::outside)
    return Error{
        path + ": STL file ends after line " + std::to_string(line) + ", inside " +
        (state == State::solid ? "a solid (no 'endsolid'; truncated?)" : "a facet (truncated?)")};
  return mesh;
}

}  // namespace lightvol::detail

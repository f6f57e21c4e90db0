// Fuzz target: text with arbitrary bytes in every string that reaches a message or a report. The
// input is cut at its 0xFF bytes (never part of UTF-8) into a file name, a key, a value and a body.
// They go where users' strings go: the name is a description's source and a mesh file's name; the
// key and the value are a light's, a medium's and a camera's keys and values; the body is a
// description and a mesh file's contents. Each message the library returns must be valid UTF-8
// whenever every string it was made from is (values are quoted cut on character boundaries,
// core/text.h), and a report made of it the way the commands make theirs (nlohmann's dump with
// invalid bytes replaced by U+FFFD, as cli/main.cpp's json_text and the GLB writer do) must parse
// back as JSON whose strings are valid UTF-8. utf8_prefix itself is checked against its contract.
// Nothing may throw.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include <lightvol/airlight/airlight.h>
#include <lightvol/core/check.h>
#include <lightvol/core/text.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/light/light.h>

namespace {

// Whether `s` is well-formed UTF-8 (shortest forms, no surrogates, at most U+10FFFF).
bool valid_utf8(std::string_view s) {
  std::size_t i = 0;
  while (i < s.size()) {
    const auto b = static_cast<unsigned char>(s[i]);
    std::size_t n = 0;
    std::uint32_t cp = 0;
    if (b < 0x80) {
      ++i;
      continue;
    }
    if (b >= 0xC2 && b <= 0xDF) {
      n = 1;
      cp = b & 0x1F;
    } else if (b >= 0xE0 && b <= 0xEF) {
      n = 2;
      cp = b & 0x0F;
    } else if (b >= 0xF0 && b <= 0xF4) {
      n = 3;
      cp = b & 0x07;
    } else {
      return false;
    }
    if (s.size() - i <= n) return false;  // cut short
    for (std::size_t k = 1; k <= n; ++k) {
      const auto c = static_cast<unsigned char>(s[i + k]);
      if ((c & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (c & 0x3F);
    }
    if ((n == 2 && cp < 0x800) || (n == 3 && (cp < 0x10000 || cp > 0x10FFFF)) ||
        (cp >= 0xD800 && cp <= 0xDFFF))
      return false;
    i += n + 1;
  }
  return true;
}

// `s` inside a JSON string: quotes, backslashes and control characters escaped, every other byte
// (invalid UTF-8 included) as it is, for the description parser to judge.
std::string json_escaped(std::string_view s) {
  std::string out;
  for (const char c : s) {
    const auto b = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (b < 0x20) {
      static const char kHex[] = "0123456789abcdef";
      out += "\\u00";
      out += kHex[b >> 4];
      out += kHex[b & 15];
    } else {
      out += c;
    }
  }
  return out;
}

// utf8_prefix's contract: a prefix of at most `max` bytes (s itself when it fits), at most 3 bytes
// shorter than the cut, and valid UTF-8 when `s` is.
void check_prefix(std::string_view s, std::size_t max) {
  const std::string p = lightvol::utf8_prefix(s, max);
  LV_CHECK(s.substr(0, p.size()) == p);
  if (s.size() <= max) {
    LV_CHECK(p.size() == s.size());
  } else {
    LV_CHECK(p.size() <= max && p.size() + 3 >= max);
  }
  if (valid_utf8(s)) LV_CHECK(valid_utf8(p));
}

// A report of `message` as the commands write one; it must parse back with valid strings.
void check_report(const std::string& name, const std::string& key, const std::string& message) {
  const nlohmann::ordered_json report = {
      {"mesh", name}, {"key", key}, {"error", message}, {"ok", false}};
  const std::string text =
      report.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
  const nlohmann::json back = nlohmann::json::parse(text);  // throws (and fails) if not JSON
  for (const auto& [k, v] : back.items()) {
    LV_CHECK(valid_utf8(k));
    if (v.is_string()) LV_CHECK(valid_utf8(v.get<std::string>()));
  }
}

// A folder of this process's own for the mesh files, removed at exit.
struct Folder {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("lightvol_fuzz_text_" + std::to_string(::getpid()));
  Folder() { std::filesystem::create_directories(path); }
  ~Folder() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Folder folder;
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> pieces;
  std::size_t at = 0;
  while (pieces.size() < 3) {
    const std::size_t cut = input.find('\xff', at);
    if (cut == std::string_view::npos) break;
    pieces.emplace_back(input.substr(at, cut - at));
    at = cut + 1;
  }
  pieces.resize(3);
  const std::string& name = pieces[0];
  const std::string& key = pieces[1];
  const std::string& value = pieces[2];
  const std::string body(input.substr(std::min(at, input.size())));

  for (const std::string* s : {&name, &key, &value, &body})
    for (const std::size_t max : {std::size_t{0}, std::size_t{1}, std::size_t{3}, std::size_t{20},
                                  std::size_t{40}, s->size() / 2, s->size()})
      check_prefix(*s, max);

  // Messages from the descriptions: the value and the key in several places, the name as the
  // source; then the body as a description.
  const std::string k = json_escaped(key), v = json_escaped(value);
  const std::string descriptions[] = {
      "{\"type\": \"" + v + "\"}",
      "{\"type\": \"spot\", \"" + k + "\": \"" + v + "\"}",
      "{\"type\": \"spot\", \"position\": [0, 0, \"" + v + "\"], \"depth\": \"" + v + "\"}",
      "{\"phase\": {\"type\": \"" + v + "\", \"" + k + "\": 1}}",
      "{\"" + k + "\": {\"" + k + "\": [\"" + v + "\"]}}",
      body,
  };
  std::vector<std::pair<std::string, bool>> messages;  // and whether its strings were all UTF-8
  const bool text_ok = valid_utf8(name) && valid_utf8(key) && valid_utf8(value);
  for (const std::string& text : descriptions) {
    const bool ok = text_ok && valid_utf8(text);
    if (auto light = lightvol::parse_light(text, name); !light)
      messages.emplace_back(light.error().message, ok);
    if (auto medium = lightvol::parse_medium(text, name); !medium)
      messages.emplace_back(medium.error().message, ok);
    if (auto camera = lightvol::parse_camera(text, name); !camera)
      messages.emplace_back(camera.error().message, ok);
  }

  // Messages from the mesh readers: the body in a file named after the name (a name the file
  // system takes: no '/', at most 200 bytes), in a text format the key's length picks.
  std::string file = name.substr(0, 200);
  for (char& c : file)
    if (c == '/' || c == '\0') c = '_';
  if (file.empty() || file == "." || file == "..") file = "x";
  static const char* const kExtensions[] = {".ply", ".off", ".obj", ".stl"};
  const std::string path = (folder.path / (file + kExtensions[key.size() % 4])).string();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
  }
  if (auto mesh = lightvol::read_mesh(path); !mesh)
    messages.emplace_back(mesh.error().message, valid_utf8(path) && valid_utf8(body));
  std::error_code ec;
  std::filesystem::remove(path, ec);
  if (auto missing = lightvol::read_mesh(path); !missing)
    messages.emplace_back(missing.error().message, valid_utf8(path));

  for (const auto& [message, from_utf8] : messages) {
    if (from_utf8 && !valid_utf8(message)) {
      std::fprintf(stderr, "a message made of UTF-8 is not UTF-8: %s\n", message.c_str());
      LV_CHECK(false);
    }
    check_report(name, key, message);
  }
  return 0;
}

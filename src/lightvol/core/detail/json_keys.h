// Reading the small JSON descriptions (light, medium, camera): parsing with every failure as a
// message, and typed keys whose problems are worded "<source>: key '<k>': ...". Internal to the
// library (it exposes nlohmann::json, which the installed headers do not need).
#pragma once

#include <array>
#include <functional>
#include <initializer_list>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include <lightvol/core/math.h>
#include <lightvol/core/result.h>
#include <lightvol/core/text_file.h>  // read_text_file, for the descriptions

namespace lightvol {

// `x` as a message shows it (stream formatting: 0.1, 1e+30).
std::string format_number(double x);

// `v` as a message quotes it: its type and at most about 80 characters of its JSON text (without
// walking more of it than that, however deep or long it is).
std::string describe_json(const nlohmann::json& v);
// A string from the input as a message quotes it: at most about 80 characters, in double quotes.
std::string quote_text(std::string_view s);

// Thrown by strict_json_check's callback: the text is JSON, but refused (`why`).
struct JsonRefused {
  std::string why;
};

// A callback for nlohmann::json::parse that throws JsonRefused for nesting deeper than 32 levels
// (else a line of '[' nests without bound) and for a key repeated in one object (else the last
// would win silently), worded by `repeated(key)`. It keeps its own state: one per parse.
nlohmann::json::parser_callback_t strict_json_check(
    std::function<std::string(const std::string& key)> repeated);

// `text` as a JSON object. Malformed JSON, numbers beyond double's range (1e99999), a NUL byte,
// a key repeated in one object, nesting deeper than 32 levels and anything but an object are
// errors naming `source`; `what` says what the object describes ("a light").
Result<nlohmann::json> parse_json_object(std::string_view text, const std::string& source,
                                         const char* what);

// Typed keys of one JSON object. `prefix` names a nested object in messages ("phase." gives
// "key 'phase.g'").
class KeyReader {
 public:
  KeyReader(const nlohmann::json& object, const std::string& source, std::string prefix = "")
      : obj_(object), source_(source), prefix_(std::move(prefix)) {}

  Error error(const std::string& key, const std::string& why) const;
  bool has(const std::string& key) const { return obj_.contains(key); }

  // The first key not in `known`, as "unknown key (known: a, b, c)".
  Status only(std::initializer_list<std::string_view> known) const;

  Result<double> number(const std::string& key) const;  // finite
  Result<Vec3d> vec3(const std::string& key) const;     // 3 finite numbers
  Result<std::array<double, 4>> array4(const std::string& key) const;
  Result<Mat4d> matrix(const std::string& key) const;  // row-major: 16 numbers or 4 rows of 4
  Result<std::string> string(const std::string& key) const;
  Result<bool> boolean(const std::string& key) const;
  // A nested object, read with the prefix "<key>.".
  Result<KeyReader> object(const std::string& key) const;

 private:
  Error missing(const std::string& key) const { return error(key, "missing"); }

  const nlohmann::json& obj_;
  const std::string& source_;
  std::string prefix_;
};

}  // namespace lightvol

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>
#include <vector>

#include <lightvol/core/detail/json_keys.h>
#include <lightvol/core/text.h>

namespace lightvol {
namespace {

using nlohmann::json;

bool is_finite_number(const json& x) { return x.is_number() && std::isfinite(x.get<double>()); }

constexpr std::size_t kQuoteLimit = 80;

// JSON text that is valid UTF-8 whatever `v`'s strings hold (a quote cut, a Latin-1 name): a byte
// that is not UTF-8 becomes U+FFFD.
std::string dump_text(const json& v) {
  return v.dump(-1, ' ', false, json::error_handler_t::replace);
}

// Appends `v`'s JSON text to `out` until `out` holds more than kQuoteLimit characters. Recursion
// stops with the text: each level adds at least one character, so it is at most kQuoteLimit deep.
void dump_bounded(const json& v, std::string* out) {
  if (out->size() > kQuoteLimit) return;
  if (v.is_array() || v.is_object()) {
    const bool object = v.is_object();
    *out += object ? '{' : '[';
    bool first = true;
    for (auto it = v.begin(); it != v.end() && out->size() <= kQuoteLimit; ++it) {
      if (!first) *out += ',';
      first = false;
      if (object) *out += dump_text(json(it.key())) + ':';
      dump_bounded(it.value(), out);
    }
    *out += object ? '}' : ']';
  } else if (v.is_string()) {
    const std::string& s = v.get_ref<const std::string&>();
    *out += dump_text(json(utf8_prefix(s, kQuoteLimit + 1)));
  } else {
    *out += dump_text(v);
  }
}

std::string describe(const json& v) { return describe_json(v); }

constexpr int kMaxDepth = 32;

}  // namespace

json::parser_callback_t strict_json_check(
    std::function<std::string(const std::string& key)> repeated) {
  // Keys per open object, shared by the copies the parser makes of the callback.
  auto open_keys = std::make_shared<std::vector<std::vector<std::string>>>();
  return [open_keys, repeated = std::move(repeated)](int depth, json::parse_event_t event,
                                                     json& parsed) {
    if (depth > kMaxDepth)
      throw JsonRefused{"nested deeper than " + std::to_string(kMaxDepth) + " levels"};
    if (event == json::parse_event_t::object_start) {
      open_keys->emplace_back();
    } else if (event == json::parse_event_t::object_end) {
      if (!open_keys->empty()) open_keys->pop_back();
    } else if (event == json::parse_event_t::key && !open_keys->empty()) {
      const std::string& key = parsed.get_ref<const std::string&>();
      std::vector<std::string>& seen = open_keys->back();
      if (std::find(seen.begin(), seen.end(), key) != seen.end()) throw JsonRefused{repeated(key)};
      seen.push_back(key);
    }
    return true;
  };
}

std::string describe_json(const json& v) {
  std::string s;
  dump_bounded(v, &s);
  if (s.size() > kQuoteLimit) s = utf8_prefix(s, kQuoteLimit - 3) + "...";
  return std::string(v.type_name()) + " " + s;
}

std::string quote_text(std::string_view s) {
  std::string q = dump_text(json(utf8_prefix(s, kQuoteLimit + 1)));
  if (q.size() > kQuoteLimit) q = utf8_prefix(q, kQuoteLimit - 4) + "...\"";
  return q;
}

std::string format_number(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

Result<json> parse_json_object(std::string_view text, const std::string& source, const char* what) {
  if (const std::size_t nul = text.find('\0'); nul != std::string_view::npos)
    return Error{source + ": byte " + std::to_string(nul) +
                 " is NUL; a description is JSON text, which has none"};
  json root;
  const json::parser_callback_t check = strict_json_check([](const std::string& key) {
    return "key " + quote_text(key) + " appears twice in one object";
  });
  try {
    root = json::parse(text.begin(), text.end(), check);
  } catch (const JsonRefused& r) {
    return Error{source + ": " + r.why};
  } catch (const json::exception& e) {  // parse_error, and out_of_range for numbers like 1e99999
    // The parser quotes what it last read as raw bytes, which may end inside a UTF-8 character:
    // each byte that is not UTF-8 becomes U+FFFD.
    const std::string message = json::parse(dump_text(json(e.what()))).get<std::string>();
    const auto at = message.find("parse error");
    return Error{source +
                 ": not valid JSON: " + (at == std::string::npos ? message : message.substr(at))};
  }
  if (!root.is_object()) return Error{source + ": expected a JSON object describing " + what};
  return root;
}

Error KeyReader::error(const std::string& key, const std::string& why) const {
  std::string name = prefix_ + key;  // unknown keys come from the input: quoted, not echoed whole
  if (name.size() > kQuoteLimit) name = utf8_prefix(name, kQuoteLimit - 3) + "...";
  return {source_ + ": key '" + name + "': " + why};
}

Status KeyReader::only(std::initializer_list<std::string_view> known) const {
  for (const auto& [key, value] : obj_.items()) {
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    std::string list;
    for (const std::string_view k : known) list += (list.empty() ? "" : ", ") + std::string(k);
    return error(key, "unknown key (known: " + list + ")");
  }
  return {};
}

Result<double> KeyReader::number(const std::string& key) const {
  if (!has(key)) return missing(key);
  const json& v = obj_.at(key);
  if (!v.is_number()) return error(key, "expected a number, got " + describe(v));
  const double x = v.get<double>();
  if (!std::isfinite(x)) return error(key, "expected a finite number");
  return x;
}

Result<Vec3d> KeyReader::vec3(const std::string& key) const {
  if (!has(key)) return missing(key);
  const json& v = obj_.at(key);
  if (!v.is_array() || v.size() != 3 || !std::all_of(v.begin(), v.end(), is_finite_number))
    return error(key, "expected an array of 3 finite numbers, got " + describe(v));
  return Vec3d{v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

Result<std::array<double, 4>> KeyReader::array4(const std::string& key) const {
  if (!has(key)) return missing(key);
  const json& v = obj_.at(key);
  if (!v.is_array() || v.size() != 4 || !std::all_of(v.begin(), v.end(), is_finite_number))
    return error(key, "expected an array of 4 finite numbers, got " + describe(v));
  return std::array<double, 4>{v[0].get<double>(), v[1].get<double>(), v[2].get<double>(),
                               v[3].get<double>()};
}

Result<Mat4d> KeyReader::matrix(const std::string& key) const {
  if (!has(key)) return missing(key);
  const json& v = obj_.at(key);
  std::vector<double> flat;
  if (v.is_array() && v.size() == 16 && std::all_of(v.begin(), v.end(), is_finite_number)) {
    for (const json& x : v) flat.push_back(x.get<double>());
  } else if (v.is_array() && v.size() == 4) {
    for (const json& row : v) {
      if (!row.is_array() || row.size() != 4 ||
          !std::all_of(row.begin(), row.end(), is_finite_number))
        break;
      for (const json& x : row) flat.push_back(x.get<double>());
    }
  }
  if (flat.size() != 16)
    return error(key, "expected a row-major 4x4 matrix: 16 finite numbers or 4 rows of 4");
  Mat4d m;
  std::copy(flat.begin(), flat.end(), m.m.begin());
  return m;
}

Result<std::string> KeyReader::string(const std::string& key) const {
  if (!has(key)) return missing(key);
  const json& v = obj_.at(key);
  if (!v.is_string()) return error(key, "expected a string, got " + describe(v));
  return v.get<std::string>();
}

Result<bool> KeyReader::boolean(const std::string& key) const {
  if (!has(key)) return missing(key);
  const json& v = obj_.at(key);
  if (!v.is_boolean()) return error(key, "expected true or false, got " + describe(v));
  return v.get<bool>();
}

Result<KeyReader> KeyReader::object(const std::string& key) const {
  if (!has(key)) return missing(key);
  const json& v = obj_.at(key);
  if (!v.is_object()) return error(key, "expected an object, got " + describe(v));
  return KeyReader(v, source_, prefix_ + key + ".");
}

}  // namespace lightvol

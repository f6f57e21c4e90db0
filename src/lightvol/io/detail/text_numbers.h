// Numbers in the text mesh formats (OBJ, OFF, ASCII PLY, ASCII STL): one strict parse for every
// reader, so that a coordinate is either a finite float or an Error naming the line. (OpenMesh's
// ASCII STL reader left a coordinate it could not read, "nan" or "abc", as whatever the memory
// held; 1e39 became infinity.)
// Internal to the library.
#pragma once

#include <charconv>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>

#include <lightvol/core/text.h>

namespace lightvol::detail {

// A number spanning all of `word`: decimal, optionally scientific, with an optional sign ("+1.5"
// too). As std::from_chars does, it takes "nan" and "inf" (for values that are skipped); a value
// beyond a double is refused.
inline bool parse_number(std::string_view word, double* value) {
  if (word.size() > 1 && word[0] == '+' && word[1] != '-' && word[1] != '+') word.remove_prefix(1);
  if (word.empty()) return false;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), *value);
  return ec == std::errc() && end == word.data() + word.size();
}

// A vertex coordinate: a number whose magnitude is at most the largest float (3.4e38). "nan",
// "inf", "abc" and 1e39 are refused.
inline bool parse_coordinate(std::string_view word, float* value) {
  double d = 0;
  if (!parse_number(word, &d)) return false;
  constexpr double kMax = std::numeric_limits<float>::max();
  if (!(d >= -kMax && d <= kMax)) return false;  // NaN too
  *value = static_cast<float>(d);
  return true;
}

// What is wrong with a word parse_coordinate refused, quoting at most 40 bytes of it.
inline std::string not_a_coordinate(std::string_view word) {
  return "'" + utf8_prefix(word, 40) +
         "' is not a coordinate (a finite number within a float's range)";
}

}  // namespace lightvol::detail

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include <lightvol/core/text.h>

namespace lightvol {

std::string utf8_prefix(std::string_view s, std::size_t max_bytes) {
  if (s.size() <= max_bytes) return std::string(s);
  std::size_t end = max_bytes;
  // s[end] starts the part cut off: while it continues a character, the cut moves back.
  for (int step = 0; step < 3 && end > 0 && (static_cast<unsigned char>(s[end]) & 0xC0) == 0x80;
       ++step)
    --end;
  if ((static_cast<unsigned char>(s[end]) & 0xC0) == 0x80) end = max_bytes;  // not UTF-8 there
  return std::string(s.substr(0, end));
}

namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }

// The length of the digits at `s[i]`.
std::size_t digits_at(std::string_view s, std::size_t i) {
  std::size_t n = 0;
  while (i + n < s.size() && is_digit(s[i + n])) ++n;
  return n;
}

}  // namespace

std::optional<double> parse_decimal(std::string_view text) {
  std::size_t i = 0;
  if (i < text.size() && text[i] == '-') ++i;
  const std::size_t whole = digits_at(text, i);
  i += whole;
  std::size_t fraction = 0;
  if (i < text.size() && text[i] == '.') {
    fraction = digits_at(text, i + 1);
    i += 1 + fraction;
  }
  if (whole + fraction == 0) return std::nullopt;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    std::size_t k = i + 1;
    if (k < text.size() && (text[k] == '+' || text[k] == '-')) ++k;
    const std::size_t exponent = digits_at(text, k);
    if (exponent == 0) return std::nullopt;
    i = k + exponent;
  }
  if (i != text.size()) return std::nullopt;
  // The grammar above is a subset of strtod's, which now reads exactly these characters.
  const std::string copy(text);
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(copy.c_str(), &end);
  if (end != copy.c_str() + copy.size() || !std::isfinite(value)) return std::nullopt;
  if (errno == ERANGE && std::fabs(value) > 1) return std::nullopt;  // overflow; underflow is 0
  return value;
}

std::optional<long long> parse_decimal_integer(std::string_view text) {
  const std::size_t sign = !text.empty() && text[0] == '-' ? 1 : 0;
  const std::size_t digits = digits_at(text, sign);
  if (digits == 0 || sign + digits != text.size()) return std::nullopt;
  const std::string copy(text);
  errno = 0;
  char* end = nullptr;
  const long long value = std::strtoll(copy.c_str(), &end, 10);
  if (errno == ERANGE || end != copy.c_str() + copy.size()) return std::nullopt;
  return value;
}

std::string thousands(unsigned long long n) {
  std::string digits = std::to_string(n), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

}  // namespace lightvol

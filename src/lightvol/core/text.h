// Text that reaches messages and reports: UTF-8 cut on character boundaries.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace lightvol {

// The longest prefix of `s` of at most `max_bytes` bytes that does not end inside a UTF-8
// character (a cut steps back over at most 3 continuation bytes; bytes that are not UTF-8 are cut
// anywhere).
std::string utf8_prefix(std::string_view s, std::size_t max_bytes);

// A count for people: 33538050 as "33,538,050".
std::string thousands(unsigned long long n);

// A number as a flag or a list on a command line gives it, in decimal only: an optional '-',
// digits with at most one '.' (at least one digit), then an optional exponent (e or E, an
// optional sign, digits). Nothing else: no spaces, no '+' in front, no hexadecimal (0x10), no
// inf or nan, no suffix. nullopt for anything else, and for a value beyond double's range (1e999).
// Every numeric flag of the command line is read by this one rule (docs/robustness.md).
std::optional<double> parse_decimal(std::string_view text);

// An integer in decimal digits with an optional '-' (no '.', no exponent), within long long's
// range; nullopt otherwise.
std::optional<long long> parse_decimal_integer(std::string_view text);

}  // namespace lightvol

// Text that reaches messages and reports: UTF-8 cut on character boundaries.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace lightvol {

// The longest prefix of `s` of at most `max_bytes` bytes that does not end inside a UTF-8
// character (a cut steps back over at most 3 continuation bytes; bytes that are not UTF-8 are cut
// anywhere).
std::string utf8_prefix(std::string_view s, std::size_t max_bytes);

}  // namespace lightvol

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

}  // namespace lightvol

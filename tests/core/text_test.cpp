#include <gtest/gtest.h>

#include <lightvol/core/text.h>

namespace lightvol {
namespace {

TEST(Text, Utf8PrefixCutsOnCharacterBoundaries) {
  EXPECT_EQ(utf8_prefix("abc", 5), "abc");
  EXPECT_EQ(utf8_prefix("abc", 2), "ab");
  EXPECT_EQ(utf8_prefix("a\xc3\xa9", 2), "a");                            // é cut in two: dropped
  EXPECT_EQ(utf8_prefix("a\xc3\xa9z", 3), "a\xc3\xa9");                   // whole: kept
  EXPECT_EQ(utf8_prefix("\xf0\x9f\x98\x80!", 3), "");                     // a 4-byte character
  EXPECT_EQ(utf8_prefix("\xf0\x9f\x98\x80!", 4), "\xf0\x9f\x98\x80");     // whole
  EXPECT_EQ(utf8_prefix("\x80\x80\x80\x80\x80", 4), "\x80\x80\x80\x80");  // not UTF-8: any cut
}

}  // namespace
}  // namespace lightvol

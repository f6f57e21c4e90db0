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

// Before: each flag read numbers its own way (std::stod took 0x10 as 16, CLI11 took hexadecimal,
// octal and binary integers, and " 3"). One rule now: decimal digits.
TEST(Text, NumbersAreDecimalOnly) {
  EXPECT_EQ(parse_decimal("16"), 16.0);
  EXPECT_EQ(parse_decimal("-0.25"), -0.25);
  EXPECT_EQ(parse_decimal(".5"), 0.5);
  EXPECT_EQ(parse_decimal("3."), 3.0);
  EXPECT_EQ(parse_decimal("1e-3"), 1e-3);
  EXPECT_EQ(parse_decimal("2.5E+2"), 250.0);
  EXPECT_EQ(parse_decimal("1e-400"), 0.0);  // below double's range: zero
  for (const char* bad :
       {"",  "0x10", "0X1p4", "inf", "-inf", "nan",   "infinity", " 3",    "3 ", "+3",  "1e999",
        ".", "-",    "e5",    "1e",  "1e+",  "1.2.3", "1,5",      "0b101", "3f", "--3", "1e5.0"})
    EXPECT_FALSE(parse_decimal(bad).has_value()) << bad;
  EXPECT_EQ(parse_decimal_integer("30"), 30);
  EXPECT_EQ(parse_decimal_integer("-7"), -7);
  EXPECT_EQ(parse_decimal_integer("007"), 7);  // leading zeros are decimal, not octal
  for (const char* bad :
       {"", "0x10", "0b11", "0o17", "1e3", "3.0", " 3", "+3", "-", "3 ", "99999999999999999999"})
    EXPECT_FALSE(parse_decimal_integer(bad).has_value()) << bad;
}

}  // namespace
}  // namespace lightvol

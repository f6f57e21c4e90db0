#include <string>

#include <gtest/gtest.h>

#include <lightvol/core/result.h>

namespace lightvol {
namespace {

TEST(Result, HoldsAValueOrAnError) {
  const Result<int> value = 7;
  ASSERT_TRUE(value.ok());
  EXPECT_EQ(*value, 7);
  const Result<int> failed = Error{"f.json: key 'x': missing"};
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.error().message, "f.json: key 'x': missing");
  const Status success;
  EXPECT_TRUE(success.ok());
  const Status refused = Error{"f.ply: face 3: degenerate"};
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().message, "f.ply: face 3: degenerate");
}

// Asking a success for its error is a broken invariant: both abort with one line, never read an
// empty optional or the wrong alternative.
TEST(ResultDeathTest, ErrorOfASuccessAborts) {
  const Result<int> value = 7;
  EXPECT_DEATH((void)value.error(), "error\\(\\) on a successful Result");
  const Status success;
  EXPECT_DEATH((void)success.error(), "error\\(\\) on a successful Status");
  const Result<int> failed = Error{"bad"};
  EXPECT_DEATH((void)failed.value(), "value\\(\\) on a failed Result: bad");
}

}  // namespace
}  // namespace lightvol

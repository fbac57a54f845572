#include "shimmer/core/result.h"

#include <gtest/gtest.h>

#include <memory>

namespace shimmer {
namespace {

Result<int> Half(int x) {
  if (x % 2) return Result<int>::Failure("odd: " + std::to_string(x));
  return x / 2;
}

// An error travels through layers with its code; only its message grows.
Result<std::string> Describe(int x) {
  auto h = Half(x);
  if (!h) return Prefixed("half", h.failure());
  return std::to_string(*h);
}

TEST(Result, CarriesAValueOrAnErrorWithItsCode) {
  EXPECT_EQ(*Describe(8), "4");
  auto odd = Describe(3);
  ASSERT_FALSE(odd);
  EXPECT_EQ(odd.error(), "half: odd: 3");
  EXPECT_EQ(odd.code(), ErrorCode::kBadInput);
  Status io = Status::Failure("disk", ErrorCode::kIo);
  EXPECT_EQ(io.code(), ErrorCode::kIo);
  EXPECT_STREQ(ErrorCodeName(ErrorCode::kDeviceLost), "device lost");
  EXPECT_TRUE(Ok());
}

TEST(Result, HoldsMoveOnlyValues) {
  Result<std::unique_ptr<int>> r = std::make_unique<int>(7);
  ASSERT_TRUE(r);
  std::unique_ptr<int> taken = std::move(*r);
  EXPECT_EQ(*taken, 7);
}

}  // namespace
}  // namespace shimmer

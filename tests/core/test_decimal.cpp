// Load factors and times rounded to the decimals they stand for.
#include <gtest/gtest.h>

#include <cmath>

#include "core/decimal.hpp"

namespace depthfem {
namespace {

TEST(Decimal, SumsAndMultiplesOfDecimalsBecomeTheDecimals) {
  EXPECT_NE(0.28 + 0.16, 0.44);  // the binary round-off that motivates it
  EXPECT_EQ(round_to_decimal(0.28 + 0.16), 0.44);
  EXPECT_EQ(round_to_decimal(3 * 0.1), 0.3);
  EXPECT_EQ(round_to_decimal(7 * 0.3), 2.1);
  EXPECT_EQ(round_to_decimal(0.1 + 0.2), 0.3);
  // Values of 12 significant digits or fewer are kept exactly, halved increments included.
  for (const double exact : {1.0, 0.25, 0.000244140625, 1e-7, 0.96, 123456.789012})
    EXPECT_EQ(round_to_decimal(exact), exact) << exact;
  // Longer values move by less than 1e-12 of themselves.
  EXPECT_NEAR(round_to_decimal(1.0 / 3), 1.0 / 3, 1e-12 / 3);
  EXPECT_EQ(round_to_decimal(1.0 / 3), 0.333333333333);
}

}  // namespace
}  // namespace depthfem

#include "core/json_text.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace ceilpose {
namespace {

TEST(JsonQuote, QuotesPlainText) { EXPECT_EQ(json_quote("synthetic"), "\"synthetic\""); }

TEST(JsonQuote, EscapesQuotesBackslashesAndControlCharacters) {
  EXPECT_EQ(json_quote("a\"b\\c\nd\te\x01"), "\"a\\\"b\\\\c\\nd\\te\\u0001\"");
}

TEST(JsonQuote, KeepsUtf8BytesAsTheyAre) { EXPECT_EQ(json_quote("25\xC2\xB0"), "\"25\xC2\xB0\""); }

// What "%.*f" prints, read back as a number.
double printed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return std::strtod(buf, nullptr);
}

TEST(PrintableYaw, YawsNearPlusOrMinusPiPrintInsideTheHalfOpenRange) {
  for (const int decimals : {6, 7, 9}) {
    for (const double yaw : {M_PI, std::nextafter(M_PI, 0.0), -std::nextafter(M_PI, 0.0),
                             M_PI - 4e-8, -M_PI + 4e-8, -M_PI + 1e-12}) {
      const double shown = printed(printable_yaw_rad(yaw, decimals), decimals);
      EXPECT_GT(shown, -M_PI) << "yaw " << yaw << " with " << decimals << " decimals";
      EXPECT_LE(shown, M_PI) << "yaw " << yaw << " with " << decimals << " decimals";
      // Still the same direction: within one last digit of ±π.
      EXPECT_NEAR(std::fabs(shown), std::fabs(yaw), std::pow(10.0, -decimals)) << yaw;
    }
  }
  // Plain printing is what goes wrong without it.
  EXPECT_GT(printed(M_PI, 7), M_PI);
  EXPECT_LE(printed(-std::nextafter(M_PI, 0.0), 7), -M_PI);
}

TEST(PrintableYaw, OtherYawsAreUntouched) {
  for (const double yaw : {0.0, 0.5236, -1.5707963, 3.1415925, -3.1415926, 2.0}) {
    EXPECT_EQ(printable_yaw_rad(yaw, 7), yaw);
  }
  EXPECT_TRUE(std::isnan(printable_yaw_rad(NAN, 7)));
}

}  // namespace
}  // namespace ceilpose

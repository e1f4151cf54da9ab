#include "core/json_text.h"

#include <gtest/gtest.h>

namespace ceilpose {
namespace {

TEST(JsonQuote, QuotesPlainText) { EXPECT_EQ(json_quote("synthetic"), "\"synthetic\""); }

TEST(JsonQuote, EscapesQuotesBackslashesAndControlCharacters) {
  EXPECT_EQ(json_quote("a\"b\\c\nd\te\x01"), "\"a\\\"b\\\\c\\nd\\te\\u0001\"");
}

TEST(JsonQuote, KeepsUtf8BytesAsTheyAre) { EXPECT_EQ(json_quote("25\xC2\xB0"), "\"25\xC2\xB0\""); }

}  // namespace
}  // namespace ceilpose

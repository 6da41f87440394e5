// text_assertions.h — gtest assertions on message text, shared by the api tests.
#pragma once

#include <gtest/gtest.h>

#include <string_view>

namespace manipid::api::test_support {

/// EXPECT_TRUE(contains(message, part)) prints both on failure (gmock is not linked).
inline ::testing::AssertionResult contains(std::string_view text, std::string_view part) {
  if (text.find(part) != std::string_view::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' does not contain '" << part << "'";
}

}  // namespace manipid::api::test_support

// input_error_expectations.h — test helpers that run a call and look at the InputError it throws.
#pragma once

#include "manipid/core/errors.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>

namespace manipid::test_support {

/// Runs `action` and checks that it throws InputError naming `field`; returns the message.
inline std::string expect_input_error(const std::function<void()>& action, const std::string& field) {
  try {
    action();
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), field) << error.what();
    return error.what();
  }
  ADD_FAILURE() << "expected InputError(" << field << ")";
  return {};
}

/// The field of the InputError `call` throws, or "(no InputError)".
inline std::string field_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const InputError& error) {
    return error.field();
  }
  return "(no InputError)";
}

}  // namespace manipid::test_support

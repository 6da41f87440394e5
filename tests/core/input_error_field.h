// input_error_field.h — a test helper: the field a call's InputError names, or "no error".
#pragma once

#include "manipid/core/errors.h"

#include <string>

namespace manipid::testing {

template <class Call>
std::string input_error_field(Call&& call) {
  try {
    call();
  } catch (const InputError& error) {
    return error.field();
  }
  return "no error";
}

}  // namespace manipid::testing

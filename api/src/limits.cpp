// limits.cpp — the dataset size checks of limits.h, with messages that say what was asked for,
// what is allowed and why.
#include "manipid/api/limits.h"

#include "manipid/core/errors.h"

namespace manipid::api::limits {

long long dataset_values(long long samples, int joints, int blocks) {
  return samples * (1 + static_cast<long long>(blocks) * joints);
}

void check_joints(int joints, const std::string& field, const std::string& what) {
  if (joints > max_joints) {
    throw InputError(field, what + " has " + std::to_string(joints) + " joints; at most " + std::to_string(max_joints) +
                                " are allowed");
  }
}

void check_dataset_size(long long samples, int joints, int blocks, const std::string& field, const std::string& what) {
  if (samples > max_samples) {
    throw InputError(field, what + " gives " + std::to_string(samples) + " samples; at most " +
                                std::to_string(max_samples) + " are allowed");
  }
  check_joints(joints, field, "the dataset");
  const long long values = dataset_values(samples, joints, blocks);
  if (values > max_values) {
    const long long columns = 1 + static_cast<long long>(blocks) * joints;
    throw InputError(field, what + " gives " + std::to_string(samples) + " samples of " + std::to_string(columns) +
                                " numbers (" + std::to_string(values) + "); a dataset holds at most " +
                                std::to_string(max_values) + ", " + std::to_string(max_values / columns) +
                                " such samples");
  }
}

}  // namespace manipid::api::limits

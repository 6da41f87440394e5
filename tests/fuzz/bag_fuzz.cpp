// bag_fuzz.cpp — libFuzzer target for ROS 2 bags (api/ros2_bag.h): bytes as a bag file, read as
// JointState messages with and without the robot's joint names, then as a dataset upload. Every input
// must end in a table or a clean InputError; any other exception escapes (libFuzzer reports it as a
// crash), as do ASan/UBSan findings. The seed corpus holds a small bag (tests/fuzz/corpus/bag).
#include "manipid/api/requests.h"
#include "manipid/api/ros2_bag.h"
#include "manipid/core/errors.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

namespace {

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "bag_fuzz: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  for (const bool named : {false, true}) {
    manipid::api::BagOptions options;
    if (named) options.joint_names = {"a", "b"};
    try {
      const manipid::api::BagRead read = manipid::api::read_joint_states({bytes}, options);
      const auto& table = read.table;
      if (table.columns.empty() || table.columns.front() != "t" || table.data.rows() == 0) fail("a table without t or rows");
      if (static_cast<std::size_t>(table.data.cols()) != table.columns.size()) fail("columns and data disagree");
      if (table.data(0, 0) != 0.0) fail("t does not start at 0");
      for (Eigen::Index r = 1; r < table.data.rows(); ++r) {
        if (table.data(r, 0) < table.data(r - 1, 0)) fail("t is not sorted");
      }
    } catch (const manipid::InputError&) {
    }
  }
  try {
    (void)manipid::api::dataset_from_bag(bytes, {});
  } catch (const manipid::InputError&) {
  }
  return 0;
}

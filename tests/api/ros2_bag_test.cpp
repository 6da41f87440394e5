// ros2_bag_test.cpp — ROS 2 bags (api/ros2_bag.h) written here as rosbag2's sqlite3 storage writes them,
// with JointState messages serialised by hand in CDR of both byte orders: joints matched by name, time
// from stamps or receive times, split bags, skipped messages, and every refusal naming its field.
#include "manipid/api/ros2_bag.h"
#include "bag_writer.h"
#include "text_assertions.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace manipid::api {
namespace {

using test_support::BagWriter;
using test_support::CdrWriter;
using test_support::contains;
using test_support::Message;
using test_support::serialise;

constexpr std::int32_t kEpoch = 1'700'000'000;

/// Joint states of a 2-joint arm (its names in the bag's order b, a) at 1 kHz from the epoch: q = k·0.01
/// (a) and −k·0.01 (b), qd = 1, τ = k.
Message arm_state(int k) {
  Message message;
  message.sec = kEpoch + k / 1000;
  message.nanosec = static_cast<std::uint32_t>((k % 1000) * 1'000'000);
  message.name = {"b", "a"};
  message.position = {-0.01 * k, 0.01 * k};
  message.velocity = {-1.0, 1.0};
  message.effort = {-1.0 * k, 1.0 * k};
  return message;
}

BagRead read_one(const std::string& bag, const BagOptions& options = {}) { return read_joint_states({bag}, options); }

InputError bag_error(const std::vector<std::string>& files, const BagOptions& options = {}) {
  try {
    std::vector<std::string_view> views(files.begin(), files.end());
    read_joint_states(views, options);
  } catch (const InputError& error) {
    return error;
  }
  ADD_FAILURE() << "no InputError";
  return InputError("", "");
}

TEST(Ros2Bag, JointStatesAreReadByNameWithTimeFromTheStamps) {
  BagWriter writer;
  const int tf = writer.topic("/tf", "tf2_msgs/msg/TFMessage");
  const int joints = writer.topic("/joint_states", "sensor_msgs/msg/JointState");
  for (int k = 0; k < 1500; ++k) {
    writer.message(joints, 5'000'000'000LL + k * 1'000'000LL + 37, serialise(arm_state(k), k % 2 == 0));  // both byte orders
    if (k % 100 == 0) writer.message(tf, 5'000'000'000LL + k * 1'000'000LL, "\0\1\0\0not a joint state");
  }
  const std::string bag = writer.bytes();
  ASSERT_TRUE(is_sqlite_database(bag));

  BagOptions options;
  options.joint_names = {"a", "b"};  // the URDF's order, not the bag's
  const BagRead read = read_one(bag, options);
  EXPECT_EQ(read.topic, "/joint_states");
  EXPECT_EQ(read.messages, 1500u);
  EXPECT_FALSE(read.receive_times);
  EXPECT_EQ(read.table.columns, (std::vector<std::string>{"t", "q1", "q2", "qd1", "qd2", "tau1", "tau2"}));
  // From the first stamp, exact to the nanosecond: 1.499 s after 1.7e9 s of epoch.
  EXPECT_EQ(read.table.data(1499, 0), 1.499);
  EXPECT_EQ(read.table.data(1499, 1), 0.01 * 1499);
  EXPECT_EQ(read.table.data(1499, 2), -0.01 * 1499);
  EXPECT_EQ(read.table.data(3, 3), 1.0);
  EXPECT_EQ(read.table.data(3, 6), -3.0);
  EXPECT_TRUE(contains(read.summary(), "topic /joint_states: 1500 messages, 2 joints (a, b), t from the header stamps"));

  // Without names: the bag's own order.
  const BagRead own = read_one(bag);
  EXPECT_EQ(own.joints, (std::vector<std::string>{"b", "a"}));
  EXPECT_EQ(own.table.data(10, 1), -0.1);
}

TEST(Ros2Bag, ZeroStampsFallBackToReceiveTimesAndOtherJointsAreSkipped) {
  BagWriter writer;
  const int joints = writer.topic("/joint_states", "sensor_msgs/msg/JointState");
  for (int k = 0; k < 20; ++k) {
    Message message = arm_state(k);
    message.sec = 0;
    message.nanosec = 0;
    message.effort.clear();  // allowed: a driver without torque
    writer.message(joints, 1'000'000LL * (20 - k), serialise(message));  // stored out of order
    Message gripper;
    gripper.name = {"finger"};
    gripper.position = {0.02};
    writer.message(joints, 1'000'000LL * (20 - k) + 1, serialise(gripper));
  }
  BagOptions options;
  options.joint_names = {"a", "b"};
  const BagRead read = read_one(writer.bytes(), options);
  EXPECT_TRUE(read.receive_times);
  EXPECT_EQ(read.messages, 20u);
  EXPECT_EQ(read.skipped, 20u);
  EXPECT_EQ(read.table.columns, (std::vector<std::string>{"t", "q1", "q2", "qd1", "qd2"}));
  // Sorted by receive time: the last message written (k = 19) first.
  EXPECT_EQ(read.table.data(0, 0), 0.0);
  EXPECT_EQ(read.table.data(0, 1), 0.19);
  EXPECT_NEAR(read.table.data(19, 0), 0.019, 1e-15);
  EXPECT_TRUE(contains(read.summary(), "20 messages without every joint skipped"));
}

TEST(Ros2Bag, AnEmptyVelocityBeforeTheEffortsIsNotPadded) {
  // CDR aligns a sequence's elements, and an empty one has none: the effort count follows the velocity
  // count directly (after a 4-byte count ending on a multiple of 8, no 4 bytes of padding).
  BagWriter writer;
  const int joints = writer.topic("/joint_states", "sensor_msgs/msg/JointState");
  for (int k = 0; k < 3; ++k) {
    Message message = arm_state(k);
    message.velocity.clear();
    for (bool little : {true, false}) writer.message(joints, 2 * k + (little ? 0 : 1), serialise(message, little));
  }
  const BagRead read = read_one(writer.bytes());
  EXPECT_EQ(read.table.columns, (std::vector<std::string>{"t", "q1", "q2", "tau1", "tau2"}));
  EXPECT_EQ(read.table.data(4, 3), -2.0);
  EXPECT_EQ(read.table.data(5, 4), 2.0);
}

TEST(Ros2Bag, ASplitBagIsReadAsOne) {
  BagWriter first, second;
  const int a = first.topic("/joint_states", "sensor_msgs/msg/JointState");
  const int b = second.topic("/joint_states", "sensor_msgs/msg/JointState");
  for (int k = 0; k < 10; ++k) first.message(a, k, serialise(arm_state(k)));
  for (int k = 10; k < 25; ++k) second.message(b, k, serialise(arm_state(k)));
  const std::string one = first.bytes(), two = second.bytes();
  const BagRead read = read_joint_states({one, two}, {});
  EXPECT_EQ(read.messages, 25u);
  EXPECT_EQ(read.table.data(24, 0), 0.024);
}

TEST(Ros2Bag, WhatCannotBeReadIsNamed) {
  EXPECT_TRUE(contains(bag_error({"t,q1\n0,1\n"}).what(), "not a ROS 2 bag in the sqlite3 storage (no SQLite header)"));
  EXPECT_FALSE(is_sqlite_database("t,q1\n"));

  BagWriter writer;
  const int joints = writer.topic("/joint_states", "sensor_msgs/msg/JointState");
  writer.topic("/other_states", "sensor_msgs/msg/JointState");
  writer.topic("/tf", "tf2_msgs/msg/TFMessage");
  for (int k = 0; k < 5; ++k) writer.message(joints, k, serialise(arm_state(k)));
  const std::string bag = writer.bytes();

  // A damaged file: its pages cut short.
  EXPECT_TRUE(contains(bag_error({bag.substr(0, bag.size() / 2)}).what(), "not a ROS 2 bag"));

  InputError error = bag_error({bag});
  EXPECT_EQ(error.field(), "topic");
  EXPECT_TRUE(contains(error.what(), "2 JointState topics (/joint_states, /other_states): name one (--topic"));
  BagOptions options;
  options.topic = "/tf";
  EXPECT_TRUE(contains(bag_error({bag}, options).what(), "topic /tf in the bag holds tf2_msgs/msg/TFMessage"));
  options.topic = "/missing";
  error = bag_error({bag}, options);
  EXPECT_EQ(error.field(), "topic");
  EXPECT_TRUE(contains(error.what(), "no topic /missing in the bag; its topics: /joint_states (sensor_msgs/msg/JointState)"));
  options.topic = "/other_states";
  EXPECT_TRUE(contains(bag_error({bag}, options).what(), "topic /other_states has no messages"));

  options.topic = "/joint_states";
  options.joint_names = {"shoulder", "elbow"};
  error = bag_error({bag}, options);
  EXPECT_EQ(error.field(), "bag");
  EXPECT_TRUE(contains(error.what(), "no message on /joint_states names every joint of the robot (shoulder, elbow); the first "
                                     "names b, a: is this the bag of this arm?"));
}

TEST(Ros2Bag, MalformedMessagesAreRefusedNotRead) {
  const std::string good = serialise(arm_state(3));
  const auto refused = [](const std::string& data) {
    BagWriter writer;
    writer.message(writer.topic("/joint_states", "sensor_msgs/msg/JointState"), 0, data);
    return bag_error({writer.bytes()});
  };
  EXPECT_TRUE(contains(refused(good.substr(0, good.size() - 3)).what(), "message 1 on /joint_states is not a readable "
                                                                        "JointState: it ends early"));
  EXPECT_TRUE(contains(refused("\0\1").what(), "shorter than its 4-byte encapsulation header"));
  EXPECT_TRUE(contains(refused(std::string("\0\x0b\0\0", 4) + good.substr(4)).what(), "not plain CDR"));
  // A name sequence that claims four billion elements.
  CdrWriter cdr(true);
  cdr.uint32(1);
  cdr.uint32(0);
  cdr.string("");
  cdr.uint32(0xFFFFFFFFu);
  EXPECT_TRUE(contains(refused(cdr.bytes()).what(), "its name sequence claims 4294967295 elements"));
  // Names and positions of different lengths.
  Message uneven = arm_state(1);
  uneven.position.pop_back();
  EXPECT_TRUE(contains(refused(serialise(uneven)).what(), "2 names but 1 positions"));
}

}  // namespace
}  // namespace manipid::api

// ros2_bag.h — ROS 2 bags in the sqlite3 storage (.db3) of sensor_msgs/msg/JointState read as manipid's
// columns: t (s, from the first message), q1..qn, qd1..qdn and tau1..taun, the joints matched by name.
//
// A bag is a SQLite database (tables topics and messages, rosbag2's sqlite3 storage plugin) whose
// messages are CDR-serialised (XCDR1, either byte order). A JointState carries
//     std_msgs/Header header  (stamp: int32 sec, uint32 nanosec; string frame_id)
//     string[] name; float64[] position, velocity, effort
// — SI units, link-side joint values — so no column map or unit applies. The bag is untrusted input:
// it is opened read-only from memory in SQLite's defensive mode after a quick_check, and every CDR
// read is bounds-checked; a bag that cannot be used is an InputError naming the field ("bag" or
// "topic") and what to do. MCAP bags are not read (Debian packages no MCAP library): convert them with
// `ros2 bag convert` to the sqlite3 storage.
#pragma once

#include "manipid/api/csv.h"

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace manipid::api {

struct BagOptions {
  std::string topic;  ///< the JointState topic; empty: the bag's only one
  /// The joints to read, in this order (a URDF's), matched by name in every message; messages that lack
  /// one are skipped (a gripper's own JointState). Empty: the joints of the topic's first message.
  std::vector<std::string> joint_names;
};

struct BagRead {
  CsvTable table;                   ///< t, q1..qn, then qd1..qdn and tau1..taun when every message has them
  std::string topic;                ///< the topic read
  std::vector<std::string> joints;  ///< the joint names, in column order
  std::size_t messages = 0;         ///< messages read
  std::size_t skipped = 0;          ///< messages without every joint
  bool receive_times = false;       ///< t from the bag's receive times (the header stamps were zero)
  /// One line for a log: "topic /joint_states: 12000 messages, 7 joints (…), t from the header stamps".
  std::string summary() const;
};

/// Whether `bytes` begins as a SQLite database does ("SQLite format 3\0").
bool is_sqlite_database(std::string_view bytes);

/// Reads the JointState messages of one bag (several files: a split bag's, in order). Throws InputError.
BagRead read_joint_states(const std::vector<std::string_view>& files, const BagOptions& options);

}  // namespace manipid::api

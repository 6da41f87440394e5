// ros2_bag.cpp — sensor_msgs/msg/JointState from a rosbag2 sqlite3 bag (ros2_bag.h).
#include "manipid/api/ros2_bag.h"

#include "manipid/api/limits.h"
#include "manipid/core/errors.h"

#include <sqlite3.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>

namespace manipid::api {
namespace {

constexpr std::string_view kSqliteMagic{"SQLite format 3\0", 16};
constexpr const char* kJointState = "sensor_msgs/msg/JointState";

// ---- CDR (XCDR1): primitives aligned to their size, relative to the body after the 4-byte header ----

class CdrReader {
 public:
  /// `message` is one serialised message; `where` names it in errors ("message 12 on /joint_states").
  CdrReader(std::string_view message, std::string where) : where_(std::move(where)) {
    if (message.size() < 4) fail("shorter than its 4-byte encapsulation header");
    // Representation identifier: 0x0000 CDR big-endian, 0x0001 CDR little-endian (what ROS 2 writes).
    if (message[0] != 0 || (message[1] != 0 && message[1] != 1)) {
      fail("not plain CDR (encapsulation " + std::to_string(static_cast<unsigned char>(message[0])) + "," +
           std::to_string(static_cast<unsigned char>(message[1])) + ")");
    }
    little_ = message[1] == 1;
    body_ = message.substr(4);
  }

  std::uint32_t uint32() { return read<std::uint32_t>(); }
  std::int32_t int32() { return static_cast<std::int32_t>(read<std::uint32_t>()); }
  double float64() {
    const std::uint64_t bits = read<std::uint64_t>();
    double value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  std::string string() {
    const std::uint32_t length = uint32();  // with its terminating NUL
    need(length);
    std::string text(body_.substr(at_, length));
    at_ += length;
    if (!text.empty() && text.back() == '\0') text.pop_back();
    return text;
  }
  /// A sequence's element count, checked against the bytes left (each element at least `element_bytes`).
  std::uint32_t count(std::size_t element_bytes, const char* what) {
    const std::uint32_t n = uint32();
    if (static_cast<std::size_t>(n) * element_bytes > body_.size() - at_) {
      fail(std::string("its ") + what + " sequence claims " + std::to_string(n) + " elements, more than the message holds");
    }
    return n;
  }
  std::vector<double> doubles(const char* what) {
    const std::uint32_t n = count(8, what);
    std::vector<double> values(n);
    for (double& value : values) value = float64();
    return values;
  }
  [[noreturn]] void fail(const std::string& problem) const {
    throw InputError("bag", where_ + " is not a readable JointState: " + problem);
  }

 private:
  template <class T>
  T read() {
    at_ = (at_ + sizeof(T) - 1) / sizeof(T) * sizeof(T);
    need(sizeof(T));
    T value = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      const auto byte = static_cast<T>(static_cast<unsigned char>(body_[at_ + i]));
      value |= little_ ? byte << (8 * i) : byte << (8 * (sizeof(T) - 1 - i));
    }
    at_ += sizeof(T);
    return value;
  }
  void need(std::size_t bytes) const {
    if (at_ > body_.size() || bytes > body_.size() - at_) fail("it ends early");
  }

  std::string where_;
  std::string_view body_;
  std::size_t at_ = 0;
  bool little_ = true;
};

struct JointState {
  std::int64_t stamp_ns = 0;     ///< the header's stamp
  std::int64_t received_ns = 0;  ///< the bag's timestamp
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;
};

JointState parse_joint_state(std::string_view data, std::string where) {
  CdrReader cdr(data, std::move(where));
  JointState message;
  const std::int64_t sec = cdr.int32();
  const std::int64_t nanosec = cdr.uint32();
  message.stamp_ns = sec * 1'000'000'000 + nanosec;
  (void)cdr.string();  // frame_id
  const std::uint32_t names = cdr.count(5, "name");  // a string: its length and at least its NUL
  message.name.reserve(names);
  for (std::uint32_t i = 0; i < names; ++i) message.name.push_back(cdr.string());
  message.position = cdr.doubles("position");
  message.velocity = cdr.doubles("velocity");
  message.effort = cdr.doubles("effort");
  if (message.position.size() != message.name.size()) {
    cdr.fail(std::to_string(message.name.size()) + " names but " + std::to_string(message.position.size()) + " positions");
  }
  return message;
}

// ---- SQLite: the bag opened read-only from memory, defensively ----

struct Closer {
  void operator()(sqlite3* db) const { sqlite3_close(db); }
  void operator()(sqlite3_stmt* statement) const { sqlite3_finalize(statement); }
};
using Database = std::unique_ptr<sqlite3, Closer>;
using Statement = std::unique_ptr<sqlite3_stmt, Closer>;

[[noreturn]] void not_a_bag(const std::string& file, const std::string& problem) {
  throw InputError("bag", file + " is not a ROS 2 bag in the sqlite3 storage (" + problem +
                              "); MCAP bags convert with: ros2 bag convert");
}

Database open_bag(std::string_view bytes, const std::string& file) {
  if (!is_sqlite_database(bytes)) not_a_bag(file, "no SQLite header");
  sqlite3* raw = nullptr;
  if (sqlite3_open_v2(":memory:", &raw, SQLITE_OPEN_READWRITE | SQLITE_OPEN_MEMORY, nullptr) != SQLITE_OK) {
    sqlite3_close(raw);
    throw std::runtime_error("cannot open an in-memory SQLite database");
  }
  Database db(raw);
  // An untrusted database file (sqlite.org, "Defense against the dark arts").
  sqlite3_db_config(raw, SQLITE_DBCONFIG_DEFENSIVE, 1, nullptr);
  sqlite3_db_config(raw, SQLITE_DBCONFIG_TRUSTED_SCHEMA, 0, nullptr);
  sqlite3_limit(raw, SQLITE_LIMIT_LENGTH, static_cast<int>(std::min<std::size_t>(bytes.size() + 1, 1'000'000'000)));
  // READONLY: SQLite never writes to (or frees) the caller's bytes.
  auto* data = reinterpret_cast<unsigned char*>(const_cast<char*>(bytes.data()));
  if (sqlite3_deserialize(raw, "main", data, static_cast<sqlite3_int64>(bytes.size()),
                          static_cast<sqlite3_int64>(bytes.size()), SQLITE_DESERIALIZE_READONLY) != SQLITE_OK) {
    not_a_bag(file, sqlite3_errmsg(raw));
  }
  sqlite3_exec(raw, "PRAGMA cell_size_check=ON", nullptr, nullptr, nullptr);
  sqlite3_stmt* check = nullptr;
  if (sqlite3_prepare_v2(raw, "PRAGMA quick_check(1)", -1, &check, nullptr) != SQLITE_OK) not_a_bag(file, sqlite3_errmsg(raw));
  Statement checked(check);
  if (sqlite3_step(check) != SQLITE_ROW) not_a_bag(file, sqlite3_errmsg(raw));
  const auto* verdict = reinterpret_cast<const char*>(sqlite3_column_text(check, 0));
  if (verdict == nullptr || std::string_view(verdict) != "ok") not_a_bag(file, "damaged: " + std::string(verdict ? verdict : ""));
  return db;
}

Statement prepare(sqlite3* db, const char* sql, const std::string& file) {
  sqlite3_stmt* statement = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &statement, nullptr) != SQLITE_OK) not_a_bag(file, sqlite3_errmsg(db));
  return Statement(statement);
}

std::string text_column(sqlite3_stmt* statement, int column) {
  const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(statement, column));
  return text ? std::string(text, static_cast<std::size_t>(sqlite3_column_bytes(statement, column))) : std::string();
}

std::string list(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size() && i < 20; ++i) text += (i ? ", " : "") + names[i];
  if (names.size() > 20) text += ", … (" + std::to_string(names.size()) + " in all)";
  return text.empty() ? "none" : text;
}

/// The JointState topic's id in one file, chosen by name or as the only one.
std::int64_t topic_id(sqlite3* db, const std::string& file, std::string& topic) {
  Statement statement = prepare(db, "SELECT id, name, type FROM topics ORDER BY id", file);
  std::vector<std::pair<std::int64_t, std::string>> joint_states;
  std::vector<std::string> all;
  int step;
  while ((step = sqlite3_step(statement.get())) == SQLITE_ROW) {
    const std::string name = text_column(statement.get(), 1), type = text_column(statement.get(), 2);
    all.push_back(name + " (" + type + ")");
    if (type == kJointState) joint_states.emplace_back(sqlite3_column_int64(statement.get(), 0), name);
    if (!topic.empty() && name == topic) {
      if (type != kJointState) {
        throw InputError("topic", "topic " + topic + " in " + file + " holds " + type + ", not " + kJointState);
      }
      return sqlite3_column_int64(statement.get(), 0);
    }
  }
  if (step != SQLITE_DONE) not_a_bag(file, sqlite3_errmsg(db));
  if (!topic.empty()) throw InputError("topic", "no topic " + topic + " in " + file + "; its topics: " + list(all));
  if (joint_states.empty()) {
    throw InputError("topic", file + " has no " + std::string(kJointState) + " topic; its topics: " + list(all));
  }
  if (joint_states.size() > 1) {
    std::vector<std::string> names;
    for (const auto& entry : joint_states) names.push_back(entry.second);
    throw InputError("topic", file + " has " + std::to_string(names.size()) + " JointState topics (" + list(names) +
                                  "): name one (--topic, topic= in the API)");
  }
  topic = joint_states.front().second;
  return joint_states.front().first;
}

}  // namespace

bool is_sqlite_database(std::string_view bytes) { return bytes.substr(0, kSqliteMagic.size()) == kSqliteMagic; }

std::string BagRead::summary() const {
  std::string text = "topic " + topic + ": " + std::to_string(messages) + " messages, " + std::to_string(joints.size()) +
                     " joints (" + list(joints) + ")";
  if (skipped > 0) text += ", " + std::to_string(skipped) + " messages without every joint skipped";
  text += receive_times ? ", t from the bag's receive times (the header stamps are zero)" : ", t from the header stamps";
  return text;
}

BagRead read_joint_states(const std::vector<std::string_view>& files, const BagOptions& options) {
  if (files.empty()) throw InputError("bag", "no bag files given");
  BagRead read;
  read.topic = options.topic;
  read.joints = options.joint_names;  // empty: the first message's, below
  // Each message reduced at once to its row (the joints' values, in the joints' order): names are not kept.
  struct Row {
    std::int64_t stamp_ns, received_ns;
    std::size_t values;  ///< where its q (then qd, tau) begin in `values`
  };
  std::vector<Row> rows;
  std::vector<double> values;  // per row: q1..qn, qd1..qdn, tau1..taun (NaN where a message lacks them)
  bool all_velocity = true, all_effort = true, all_stamped = true;
  std::vector<std::string> first_names;
  std::size_t total = 0;
  for (std::size_t f = 0; f < files.size(); ++f) {
    const std::string file = files.size() == 1 ? "the bag" : "bag file " + std::to_string(f + 1);
    const Database db = open_bag(files[f], file);
    std::string topic = read.topic;
    const std::int64_t id = topic_id(db.get(), file, topic);
    read.topic = topic;  // every file of a split bag is read on the first one's topic
    Statement statement = prepare(db.get(), "SELECT timestamp, data FROM messages WHERE topic_id = ?1 ORDER BY timestamp, id",
                                  file);
    sqlite3_bind_int64(statement.get(), 1, id);
    int step;
    while ((step = sqlite3_step(statement.get())) == SQLITE_ROW) {
      if (total >= static_cast<std::size_t>(limits::max_samples)) {
        throw InputError("bag", "more than " + std::to_string(limits::max_samples) + " JointState messages on " + topic +
                                    " (the limit of a dataset's samples)");
      }
      const auto* blob = static_cast<const char*>(sqlite3_column_blob(statement.get(), 1));
      const auto size = static_cast<std::size_t>(sqlite3_column_bytes(statement.get(), 1));
      ++total;
      const JointState message = parse_joint_state(std::string_view(blob ? blob : "", blob ? size : 0),
                                                   "message " + std::to_string(total) + " on " + topic);
      if (total == 1) {
        first_names = message.name;
        if (read.joints.empty()) {
          if (message.name.empty()) throw InputError("bag", "the first message on " + topic + " names no joints");
          read.joints = message.name;
        }
        limits::check_joints(static_cast<int>(read.joints.size()), "bag", "the bag");
      }
      const std::size_t n = read.joints.size();
      std::vector<std::size_t> index;
      index.reserve(n);
      for (const std::string& joint : read.joints) {
        const auto found = std::find(message.name.begin(), message.name.end(), joint);
        if (found == message.name.end()) break;
        index.push_back(static_cast<std::size_t>(found - message.name.begin()));
      }
      if (index.size() != n) {
        ++read.skipped;
        continue;
      }
      const bool velocity = message.velocity.size() == message.name.size();
      const bool effort = message.effort.size() == message.name.size();
      all_velocity = all_velocity && velocity;
      all_effort = all_effort && effort;
      all_stamped = all_stamped && message.stamp_ns != 0;
      rows.push_back({message.stamp_ns, sqlite3_column_int64(statement.get(), 0), values.size()});
      const double missing = std::numeric_limits<double>::quiet_NaN();
      for (std::size_t k = 0; k < n; ++k) values.push_back(message.position[index[k]]);
      for (std::size_t k = 0; k < n; ++k) values.push_back(velocity ? message.velocity[index[k]] : missing);
      for (std::size_t k = 0; k < n; ++k) values.push_back(effort ? message.effort[index[k]] : missing);
    }
    if (step != SQLITE_DONE) not_a_bag(file, sqlite3_errmsg(db.get()));
  }
  if (total == 0) throw InputError("topic", "topic " + read.topic + " has no messages");
  const std::size_t n = read.joints.size();
  if (rows.empty()) {
    throw InputError("bag", "no message on " + read.topic + " names every joint of the robot (" + list(read.joints) +
                                "); the first names " + list(first_names) + ": is this the bag of this arm?");
  }
  read.messages = rows.size();
  read.receive_times = !all_stamped;
  const auto time_of = [&](const Row& row) { return all_stamped ? row.stamp_ns : row.received_ns; };
  std::stable_sort(rows.begin(), rows.end(), [&](const Row& a, const Row& b) { return time_of(a) < time_of(b); });
  limits::check_dataset_size(static_cast<long long>(rows.size()), static_cast<int>(n), 3, "bag", "the bag");

  CsvTable& table = read.table;
  table.columns.push_back("t");
  const auto block = [&](const char* prefix) {
    for (std::size_t k = 1; k <= n; ++k) table.columns.push_back(prefix + std::to_string(k));
  };
  block("q");
  if (all_velocity) block("qd");
  if (all_effort) block("tau");
  table.data.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(table.columns.size()));
  const std::int64_t first = time_of(rows.front());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto i = static_cast<Eigen::Index>(r);
    // Integer nanoseconds from the first message: exact before the one conversion to seconds.
    table.data(i, 0) = static_cast<double>(time_of(rows[r]) - first) * 1e-9;
    const double* row = values.data() + rows[r].values;
    Eigen::Index c = 1;
    for (std::size_t block_index = 0; block_index < 3; ++block_index) {
      if ((block_index == 1 && !all_velocity) || (block_index == 2 && !all_effort)) continue;
      for (std::size_t k = 0; k < n; ++k) table.data(i, c++) = row[block_index * n + k];
    }
  }
  return read;
}

}  // namespace manipid::api

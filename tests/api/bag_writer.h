// bag_writer.h — ROS 2 bags for the tests, written as rosbag2's sqlite3 storage writes them: JointState
// messages serialised by hand in CDR (either byte order), topics and messages in rosbag2's tables.
#pragma once

#include <sqlite3.h>

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <string>
#include <vector>

namespace manipid::api::test_support {

/// One JointState, as a driver publishes it.
struct Message {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;
};

/// XCDR1 serialisation: a 4-byte encapsulation header, then each primitive aligned to its size from the
/// body's start.
class CdrWriter {
 public:
  explicit CdrWriter(bool little) : little_(little) { bytes_ = {'\0', little ? '\1' : '\0', '\0', '\0'}; }
  void uint32(std::uint32_t value) { put(value); }
  void float64(double value) { put(std::bit_cast<std::uint64_t>(value)); }
  void string(const std::string& text) {
    uint32(static_cast<std::uint32_t>(text.size() + 1));
    bytes_ += text;
    bytes_ += '\0';
  }
  void doubles(const std::vector<double>& values) {
    uint32(static_cast<std::uint32_t>(values.size()));
    for (double value : values) float64(value);
  }
  const std::string& bytes() const { return bytes_; }

 private:
  template <class T>
  void put(T value) {
    while ((bytes_.size() - 4) % sizeof(T) != 0) bytes_ += '\0';
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      const std::size_t shift = 8 * (little_ ? i : sizeof(T) - 1 - i);
      bytes_ += static_cast<char>((value >> shift) & 0xFF);
    }
  }
  bool little_;
  std::string bytes_;
};

inline std::string serialise(const Message& message, bool little = true) {
  CdrWriter cdr(little);
  cdr.uint32(static_cast<std::uint32_t>(message.sec));
  cdr.uint32(message.nanosec);
  cdr.string("base_link");
  cdr.uint32(static_cast<std::uint32_t>(message.name.size()));
  for (const std::string& name : message.name) cdr.string(name);
  cdr.doubles(message.position);
  cdr.doubles(message.velocity);
  cdr.doubles(message.effort);
  return cdr.bytes();
}

/// A bag file's bytes: rosbag2's sqlite3 schema, topics and messages (data, receive time in ns).
class BagWriter {
 public:
  BagWriter() {
    EXPECT_EQ(sqlite3_open(":memory:", &db_), SQLITE_OK);
    exec("PRAGMA page_size=512;");  // small bags for a server's small --max-body
    exec("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
         "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
         "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
         "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, "
         "data BLOB NOT NULL);"
         "INSERT INTO schema VALUES (3, 'humble');");
  }
  ~BagWriter() { sqlite3_close(db_); }
  int topic(const std::string& name, const std::string& type) {
    sqlite3_stmt* statement = nullptr;
    sqlite3_prepare_v2(db_, "INSERT INTO topics(name, type, serialization_format, offered_qos_profiles) VALUES (?, ?, 'cdr', '')",
                       -1, &statement, nullptr);
    sqlite3_bind_text(statement, 1, name.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(statement, 2, type.c_str(), -1, SQLITE_TRANSIENT);
    EXPECT_EQ(sqlite3_step(statement), SQLITE_DONE);
    sqlite3_finalize(statement);
    return static_cast<int>(sqlite3_last_insert_rowid(db_));
  }
  void message(int topic, std::int64_t received_ns, const std::string& data) {
    sqlite3_stmt* statement = nullptr;
    sqlite3_prepare_v2(db_, "INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)", -1, &statement, nullptr);
    sqlite3_bind_int(statement, 1, topic);
    sqlite3_bind_int64(statement, 2, received_ns);
    sqlite3_bind_blob(statement, 3, data.data(), static_cast<int>(data.size()), SQLITE_TRANSIENT);
    EXPECT_EQ(sqlite3_step(statement), SQLITE_DONE);
    sqlite3_finalize(statement);
  }
  std::string bytes() const {
    sqlite3_int64 size = 0;
    unsigned char* data = sqlite3_serialize(db_, "main", &size, 0);
    std::string bytes(reinterpret_cast<const char*>(data), static_cast<std::size_t>(size));
    sqlite3_free(data);
    return bytes;
  }

 private:
  void exec(const char* sql) { EXPECT_EQ(sqlite3_exec(db_, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db_); }
  sqlite3* db_ = nullptr;
};

}  // namespace manipid::api::test_support

// encoding.cpp — value encodings every store backend shares (see encoding.h).
#include "store/encoding.h"

#include "store/store.h"

#include <stdexcept>
#include <string>

#include <array>
#include <bit>
#include <cstring>
#include <limits>

namespace manipid::server::store {

namespace {

std::uint64_t reverse_bytes(std::uint64_t value) {
  std::uint64_t reversed = 0;
  for (int byte = 0; byte < 8; ++byte) {
    reversed = (reversed << 8) | (value & 0xffu);
    value >>= 8;
  }
  return reversed;
}

constexpr std::array<const char*, 5> kStateTexts = {"queued", "running", "succeeded", "failed", "cancelled"};
/// In api::JobKind's order. robot_identification since schema 6 (SQLite) and 3 (PostgreSQL), whose migrations
/// renamed the identifications that name a robot; payload_identification since schema 7 (SQLite) and 4 (PostgreSQL).
constexpr std::array<const char*, 5> kKindTexts = {"simulation", "identification", "excitation", "robot_identification",
                                                   "payload_identification"};
static_assert(std::size(api::kJobKinds) == kKindTexts.size(), "every job kind has its name in the store");

}  // namespace

std::vector<unsigned char> encode_doubles(const double* values, std::size_t count) {
  std::vector<unsigned char> bytes(count * sizeof(double));
  for (std::size_t i = 0; i < count; ++i) {
    auto bits = std::bit_cast<std::uint64_t>(values[i]);
    if constexpr (std::endian::native == std::endian::big) bits = reverse_bytes(bits);
    std::memcpy(bytes.data() + i * sizeof(double), &bits, sizeof bits);
  }
  return bytes;
}

std::span<const unsigned char> doubles_as_stored(const double* values, std::size_t count,
                                                 std::vector<unsigned char>& scratch) {
  if constexpr (std::endian::native == std::endian::little) {
    return {reinterpret_cast<const unsigned char*>(values), count * sizeof(double)};
  } else {
    scratch = encode_doubles(values, count);
    return scratch;
  }
}

bool decode_doubles(std::span<const unsigned char> bytes, double* values, std::size_t count) {
  if (bytes.size() != count * sizeof(double)) return false;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, bytes.data() + i * sizeof(double), sizeof bits);
    if constexpr (std::endian::native == std::endian::big) bits = reverse_bytes(bits);
    values[i] = std::bit_cast<double>(bits);
  }
  return true;
}

namespace {

void check_block(const Eigen::MatrixXd& matrix, Eigen::Index samples, Eigen::Index joints, const char* name) {
  if (matrix.cols() == 0) return;
  if (matrix.rows() != samples || matrix.cols() != joints) {
    throw std::invalid_argument(std::string("Trajectory.") + name + " must be samples x joints or empty");
  }
}

}  // namespace

void check_dataset_shape(const Trajectory& data) {
  const Eigen::Index samples = data.samples();
  const Eigen::Index joints = data.joint_count();
  if (data.q.rows() != samples) throw std::invalid_argument("Trajectory.q must have one row per sample");
  check_block(data.tau, samples, joints, "tau");
  check_block(data.ref, samples, joints, "ref");
  check_block(data.qd, samples, joints, "qd");
  check_block(data.qdd, samples, joints, "qdd");
}

Trajectory decode_samples(const std::string& id, const StoredSamples& stored) {
  const auto samples = static_cast<Eigen::Index>(stored.samples);
  const auto joints = static_cast<Eigen::Index>(stored.joints);
  Trajectory data;
  data.t.resize(samples);
  data.q.resize(samples, joints);
  data.tau.resize(samples, stored.has_torque ? joints : 0);
  data.ref.resize(samples, stored.has_reference ? joints : 0);
  data.qd.resize(samples, stored.has_rates ? joints : 0);
  data.qdd.resize(samples, stored.has_accelerations ? joints : 0);
  const auto fill = [](std::span<const unsigned char> blob, double* values, Eigen::Index count) {
    return decode_doubles(blob, values, static_cast<std::size_t>(count));
  };
  const bool intact = fill(stored.t, data.t.data(), data.t.size()) && fill(stored.q, data.q.data(), data.q.size()) &&
                      fill(stored.tau, data.tau.data(), data.tau.size()) &&
                      fill(stored.ref, data.ref.data(), data.ref.size()) &&
                      fill(stored.qd, data.qd.data(), data.qd.size()) &&
                      fill(stored.qdd, data.qdd.data(), data.qdd.size());
  if (!intact) throw StoreError("dataset " + id + " has samples of the wrong size in the database");
  return data;
}

api::HistoryEntry decode_history_entry(std::int64_t index, std::optional<double> cost,
                                       std::span<const unsigned char> theta, const std::string& job_id) {
  api::HistoryEntry entry;
  entry.index = static_cast<long>(index);
  entry.cost = cost.value_or(std::numeric_limits<double>::quiet_NaN());
  entry.theta.resize(theta.size() / sizeof(double));
  if (!decode_doubles(theta, entry.theta.data(), entry.theta.size())) {
    throw StoreError("history entry of job " + job_id + " has a damaged theta in the database");
  }
  return entry;
}

const char* state_text(api::JobState state) { return kStateTexts.at(static_cast<std::size_t>(state)); }

std::optional<api::JobState> state_from_text(std::string_view text) {
  for (std::size_t i = 0; i < kStateTexts.size(); ++i) {
    if (text == kStateTexts[i]) return static_cast<api::JobState>(i);
  }
  return std::nullopt;
}

const char* kind_text(api::JobKind kind) { return kKindTexts.at(static_cast<std::size_t>(kind)); }

std::optional<api::JobKind> kind_from_text(std::string_view text) {
  for (std::size_t i = 0; i < kKindTexts.size(); ++i) {
    if (text == kKindTexts[i]) return static_cast<api::JobKind>(i);
  }
  return std::nullopt;
}

}  // namespace manipid::server::store

// encoding.cpp — value encodings every store backend shares (see encoding.h).
#include "store/encoding.h"

#include <stdexcept>
#include <string>

#include <array>
#include <bit>
#include <cstring>

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
constexpr std::array<const char*, 3> kKindTexts = {"simulation", "identification", "excitation"};

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

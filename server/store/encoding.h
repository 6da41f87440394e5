// encoding.h — how every store backend writes values and reads them back: samples and θ as
// little-endian double blobs (a dataset's samples and a history row decoded from them), and its
// own spelling of job states and kinds (the databases' format, independent of how the HTTP API
// spells them). Ids, times and page tokens are every backend's (store/rules.h).
#pragma once

#include "manipid/api/records.h"
#include "manipid/core/signal/trajectory.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace manipid::server::store {

/// Raw IEEE-754 little-endian doubles, in the given order.
std::vector<unsigned char> encode_doubles(const double* values, std::size_t count);
/// The same bytes without a copy where the machine is little-endian (the values' own memory, valid
/// while they are); elsewhere encoded into `scratch`. A dataset's blobs are as large as the dataset.
std::span<const unsigned char> doubles_as_stored(const double* values, std::size_t count,
                                                 std::vector<unsigned char>& scratch);
/// Fills `count` doubles; false when the blob does not hold exactly that many.
bool decode_doubles(std::span<const unsigned char> bytes, double* values, std::size_t count);

/// The shapes a stored dataset must have: q one row per sample; tau, ref, qd and qdd samples x
/// joints or empty. std::invalid_argument naming the block otherwise (a caller's bug, not input).
void check_dataset_shape(const Trajectory& data);

/// A stored dataset's sample columns as a backend reads them: its size, the blocks it has, and
/// their blobs (valid while the call runs).
struct StoredSamples {
  std::int64_t samples = 0;
  std::int64_t joints = 0;
  bool has_torque = false;
  bool has_reference = false;
  bool has_rates = false;
  bool has_accelerations = false;
  std::span<const unsigned char> t, q, tau, ref, qd, qdd;
};
/// The samples of dataset `id` (a block it does not have is samples x 0); StoreError when a blob
/// does not hold its block.
Trajectory decode_samples(const std::string& id, const StoredSamples& stored);

/// A stored history row of job `job_id` as an entry: a NULL cost is NaN (as NaN is stored), θ
/// the doubles of its blob (NULL: none); StoreError when the blob is not whole doubles.
api::HistoryEntry decode_history_entry(std::int64_t index, std::optional<double> cost,
                                       std::span<const unsigned char> theta, const std::string& job_id);

const char* state_text(api::JobState state);
std::optional<api::JobState> state_from_text(std::string_view text);
const char* kind_text(api::JobKind kind);
std::optional<api::JobKind> kind_from_text(std::string_view text);

}  // namespace manipid::server::store

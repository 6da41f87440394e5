// encoding.h — how every store backend writes values: samples as little-endian double blobs, and
// its own spelling of job states and kinds (the databases' format, independent of how the HTTP
// API spells them). Ids, times and page tokens are every backend's (store/rules.h).
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
/// Fills `count` doubles; false when the blob does not hold exactly that many.
bool decode_doubles(std::span<const unsigned char> bytes, double* values, std::size_t count);

/// The shapes a stored dataset must have: q one row per sample; tau, ref, qd and qdd samples x
/// joints or empty. std::invalid_argument naming the block otherwise (a caller's bug, not input).
void check_dataset_shape(const Trajectory& data);

const char* state_text(api::JobState state);
std::optional<api::JobState> state_from_text(std::string_view text);
const char* kind_text(api::JobKind kind);
std::optional<api::JobKind> kind_from_text(std::string_view text);

}  // namespace manipid::server::store

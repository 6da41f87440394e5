// limits.h — how large a dataset may be: the one owner of the sizes every door checks (JSON
// and CSV uploads, simulations, excitations, robots), so that whatever is accepted can be
// stored, exported as CSV and uploaded again.
//
// A dataset is t plus up to five blocks of one column per joint (q, tau, ref, qd, qdd). The
// SQLite store writes it as one row of little-endian doubles, and SQLite refuses a row over
// SQLITE_MAX_LENGTH (1e9 bytes by default): max_values doubles (800 MB) leave room for the
// rest of the row. Its CSV form has 1 + 5 × joints columns, which max_csv_columns admits.
#pragma once

#include <cstddef>
#include <string>

namespace manipid::api::limits {

/// Most joints of a dataset or a simulation (a stored robot: max_robot_joints).
inline constexpr int max_joints = 200;
/// Most moving joints of a stored robot's chain. Manipulators have 6 or 7, dual arms with a torso about
/// 15, snake arms up to 30; the upload computes the base parameters, whose cost grows as joints³
/// (50 joints: 1.9 s and 105 MB at the door; 100 joints took 21 s and 367 MiB on an HTTP thread).
inline constexpr int max_robot_joints = 50;
/// Most samples (time steps) of a dataset, a simulation or an excitation.
inline constexpr long long max_samples = 10'000'000;
/// Most numbers one dataset holds: samples × (1 + blocks × joints).
inline constexpr long long max_values = 100'000'000;
/// Most columns of an uploaded CSV: t and five blocks of max_joints.
inline constexpr std::size_t max_csv_columns = 1 + 5 * static_cast<std::size_t>(max_joints);
/// Bytes of the largest dataset in the store (its samples only).
inline constexpr long long max_dataset_bytes = max_values * 8;

/// Numbers a dataset of this shape holds: samples × (1 + blocks × joints).
long long dataset_values(long long samples, int joints, int blocks);

/// Throws InputError(field, ...) when `joints` is above max_joints; `what` names the thing
/// counted ("q", "the URDF chain").
void check_joints(int joints, const std::string& field, const std::string& what);

/// Throws InputError(field, ...) when `samples` is above max_samples or a dataset of
/// `samples` × (1 + blocks × joints) numbers is above max_values; `what` says where the
/// samples come from ("duration / dt", "q[0]").
void check_dataset_size(long long samples, int joints, int blocks, const std::string& field, const std::string& what);

}  // namespace manipid::api::limits

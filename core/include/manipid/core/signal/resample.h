// resample.h — real loggers' time stamps made usable: stale repeats dropped, non-uniform samples
// interpolated onto a uniform grid, gaps the filters cannot bridge refused, ramps trimmed.
//
// The differential filters assume one sample period Δ. Real logs do not have one: the Panda's
// steps range from 0.7 to 8.8 ms around a 1 ms median, and about one row in eighteen is a stale
// repeat — the previous row's values logged again under a new time stamp. Treating such a log
// as uniform moves every sample in time by up to several Δ, which the filters' derivatives turn
// into torque errors (measured: 1.89 % instead of 1.14 % validation error on the Panda). So:
//  1. rows whose every measured value equals the previous row's are dropped (they carry no new
//     measurement, and their time stamp is wrong for the values they repeat) — in runs of up to three:
//     a longer run of identical rows is the robot at rest, as measured, and is kept;
//  2. the rest are interpolated onto t0, t0 + Δ, ... by piecewise-cubic Hermite interpolation
//     with three-point slopes (exact for quadratics on any spacing, C¹), so q̈ of the
//     interpolant stays close to q̈ of the signal — linear interpolation would put a kink at
//     every logged sample;
//  3. a step longer than `max_gap` is an error naming where it is: no interpolation can
//     invent the motion inside a gap, and the filters would differentiate the guess.
// Uniform data (every step within 1e-6 relative of the first, the rule Trajectory used to
// enforce) passes through unchanged, repeats and all.
#pragma once

#include "manipid/core/signal/trajectory.h"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace manipid {

struct UniformOptions {
  /// The grid's period Δ, s; 0 = the median step of the data after dropping repeats.
  double dt = 0.0;
  /// The longest step interpolation may bridge, in units of Δ; a longer one is an InputError.
  /// 25 Δ (25 ms at 1 kHz) is far shorter than the period of any motion an identification
  /// filter passes (a 5 Hz cut-off: 200 ms) and longer than every step of the real logs seen
  /// (8.8 Δ on the Panda, 1.4 Δ on the KUKA).
  double max_gap_steps = 25.0;
};

/// What make_uniform found and did, for warnings and results.
struct TimingReport {
  bool resampled = false;      ///< false: the data was uniform and is returned unchanged
  int samples_in = 0;
  int repeats_dropped = 0;     ///< stale rows removed before interpolation
  double min_step = 0.0;       ///< s, over the data as given
  double median_step = 0.0;    ///< s, after dropping repeats
  double max_step = 0.0;       ///< s, after dropping repeats
  double dt = 0.0;             ///< s, the period of the result
  int samples_out = 0;
  /// One sentence for users when resampled ("time steps are not uniform (0.7 to 8.8 ms around
  /// a median of 1 ms; 808 repeated rows dropped): resampled onto a uniform 1 ms grid ..."),
  /// else empty.
  std::string warning() const;
};

/// The data on a uniform grid (see the file comment). Validates `data` first. Throws
/// InputError("t") for a gap longer than options.max_gap_steps · Δ (naming the times and
/// sample numbers) or a grid period outside [kShortestSamplePeriod, kLongestSamplePeriod],
/// and InputError("dt") for a bad options.dt.
Trajectory make_uniform(const Trajectory& data, const UniformOptions& options = {}, TimingReport* report = nullptr);

/// Drops the first `start` and the last `end` seconds (ramps at the start and end of a run).
/// Throws InputError("trim") for negative or non-finite amounts, or when fewer than two
/// samples would remain.
Trajectory trim(const Trajectory& data, double start, double end);

/// Everything done to measured data before it is filtered: ramps trimmed, then a uniform grid.
struct DataPreparation {
  double trim_start = 0.0;  ///< s dropped at the start (0: none)
  double trim_end = 0.0;    ///< s dropped at the end (0: none)
  UniformOptions uniform;
};

/// trim() then make_uniform(); the resampling's warning (if any) is appended to `warnings`.
Trajectory prepare_data(const Trajectory& data, const DataPreparation& options,
                        std::vector<std::string>* warnings = nullptr);

/// The same without copying data that need nothing done (no trimming, already uniform on the
/// period asked for): returns `data` itself then, else the prepared copy, kept in `storage`.
/// The same checks, errors and warning as the copying form.
const Trajectory& prepare_data(const Trajectory& data, const DataPreparation& options, std::optional<Trajectory>& storage,
                               std::vector<std::string>* warnings = nullptr);

/// Several runs prepared alike, every one onto the first one's period: each the caller's own when it needs
/// nothing done, else the prepared copy kept in `storage` (resized to the runs' count). Warnings are
/// prefixed "run i: " when there are several runs.
using PreparedRuns = std::vector<std::reference_wrapper<const Trajectory>>;
PreparedRuns prepare_runs(const std::vector<Trajectory>& runs, const DataPreparation& options,
                          std::vector<std::optional<Trajectory>>& storage, std::vector<std::string>& warnings);

}  // namespace manipid

// judge.h — the neutral judge of predicted joint torque: one fixed low-pass that does not move with any
// choice an identification makes, so figures compare across runs, options and tools.
//
// A prediction τ̂ and the measured τ of the same (uniform) run both pass one zero-phase Butterworth
// low-pass (order 4, cut-off `cutoff_hz`, signal/butterworth.h); `trim_seconds` are dropped at each end
// (the filter's start-up); the figure is the relative RMS ‖τ̂ − τ‖_F / ‖τ‖_F over the judged joints, with
// each joint's relative and absolute (N·m) RMS beside it. The states a model predicts from are the run's q
// through the same low-pass, q̇ and q̈ by central differences (one-sided at the ends) — the textbook's
// construction, so that bench/real_arms/judge.py computes the same figure from the same data.
//
// Defaults: 5 Hz and 0.3 s, the reference judge used for every real arm here (docs/method.md): above the
// motion of a manipulator's excitation, below the structural resonances and the sensor noise no rigid-body
// model explains.
#pragma once

#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <vector>

namespace manipid {

struct JudgeOptions {
  double cutoff_hz = 5.0;     ///< the low-pass's −3 dB point (of one pass), Hz
  double trim_seconds = 0.3;  ///< dropped at each end of a run, s
  /// Throws InputError("judge_cutoff") unless 0 < cutoff_hz < 1/(2 dt), InputError("judge_trim") unless
  /// 0 ≤ trim_seconds and at least 8 samples remain of `duration` seconds.
  void validate(double dt, double duration) const;
};

/// The states a model predicts from (samples × joints, the run's own samples).
struct JudgedStates {
  Eigen::MatrixXd q, qd, qdd;
};
/// q low-passed, q̇ and q̈ by central differences. `uniform` must be uniformly sampled (prepare_data).
JudgedStates judge_states(const Trajectory& uniform, const JudgeOptions& options);

/// Every column of x (samples × signals, `dt` apart) through the judge's low-pass.
Eigen::MatrixXd judge_lowpass(const Eigen::Ref<const Eigen::MatrixXd>& x, double dt, const JudgeOptions& options);

/// The samples the judge compares: [first, last] with t ≥ t_0 + trim and t ≤ t_end − trim.
struct JudgedSpan {
  Eigen::Index first = 0, last = -1;
  Eigen::Index size() const { return last - first + 1; }
};
JudgedSpan judged_span(const Eigen::Ref<const Eigen::VectorXd>& t, const JudgeOptions& options);

/// A prediction judged against the measurement.
struct TorqueScore {
  Eigen::VectorXd t;               ///< the compared instants, s
  Eigen::MatrixXd measured;        ///< low-passed τ, instants × judged joints
  Eigen::MatrixXd predicted;       ///< low-passed τ̂, the same
  Eigen::VectorXd rms_error;       ///< per judged joint, N·m (N)
  Eigen::VectorXd relative_error;  ///< per judged joint ‖τ̂ − τ‖ / ‖τ‖ (NaN for a joint with no torque)
  double overall_relative_error = 0.0;  ///< ‖τ̂ − τ‖_F / ‖τ‖_F over the judged joints
};

/// The figures of a prediction already through the judge's low-pass and trimmed (instants × joints, and their
/// times): each joint's relative and RMS error, the overall relative error.
TorqueScore score_judged(Eigen::VectorXd t, Eigen::MatrixXd measured, Eigen::MatrixXd predicted);

/// Judges `predicted` against `measured` (samples × joints, both unfiltered, on the uniform times `t`) over
/// the columns `joints` (0-based; empty = all).
TorqueScore judge_torque(const Eigen::Ref<const Eigen::VectorXd>& t, const Eigen::Ref<const Eigen::MatrixXd>& measured,
                         const Eigen::Ref<const Eigen::MatrixXd>& predicted, const std::vector<int>& joints,
                         const JudgeOptions& options);

}  // namespace manipid

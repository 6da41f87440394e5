// prediction.h — what a parameter vector predicts on a run, judged by the neutral judge (signal/judge.h):
// the torque from the judge's states by inverse dynamics, measured and predicted through the judge's
// low-pass, the ends trimmed, relative and absolute RMS per joint.
#pragma once

#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/signal/judge.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <vector>

namespace manipid::robot {

/// A prediction and the measurement it is judged against.
struct TorquePrediction {
  JudgeOptions judge;              ///< what it was judged under
  std::vector<int> joints;         ///< the judged joints (0-based); the columns below
  Eigen::VectorXd t;               ///< the compared instants, s
  Eigen::MatrixXd measured;        ///< low-passed τ, instants × judged joints
  Eigen::MatrixXd model;           ///< low-passed τ̂ = τ(q, q̇, q̈; π) from the judge's states, the same
  Eigen::VectorXd rms_error;       ///< per judged joint, N·m (N)
  Eigen::VectorXd relative_error;  ///< per judged joint ‖τ̂ − τ‖ / ‖τ‖
  double overall_relative_error = 0.0;  ///< ‖τ̂ − τ‖_F / ‖τ‖_F over the judged joints
};

/// The torque `pi` predicts on `data` (uniform samples with torque: prepare_data first), judged over `joints`
/// (0-based; empty = all). Throws InputError("tau") without torque, InputError("parameters") for a π of the
/// wrong size, and what JudgeOptions::validate throws.
TorquePrediction predict_torque(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi,
                                const Trajectory& data, const JudgeOptions& judge, const std::vector<int>& joints = {});

/// Several runs' predictions as one: instants concatenated in run order, every figure over all of them (the
/// judge and joints must agree; the first's are kept). One prediction is returned as it is.
TorquePrediction combine(const std::vector<TorquePrediction>& predictions);

}  // namespace manipid::robot

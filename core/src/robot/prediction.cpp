// prediction.cpp — inverse dynamics on the judge's states, judged (robot/prediction.h).
#include "manipid/core/robot/prediction.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/rnea.h"

#include <limits>
#include <string>

namespace manipid::robot {

TorquePrediction predict_torque(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi,
                                const Trajectory& data, const JudgeOptions& judge, const std::vector<int>& joints) {
  if (!data.has_torque()) throw InputError("tau", "the data has no tau columns to compare the prediction with");
  const int n = model.joint_count();
  if (pi.size() != layout.size(n)) {
    throw InputError("parameters", "the parameter vector has " + std::to_string(pi.size()) + " entries, the robot " +
                                       std::to_string(layout.size(n)));
  }
  if (data.joint_count() != n) {
    throw InputError("q", "the data has " + std::to_string(data.joint_count()) + " joints, the robot " + std::to_string(n));
  }
  judge.validate(data.dt(), data.t[data.samples() - 1] - data.t[0]);
  const JudgedStates states = judge_states(data, judge);
  Eigen::MatrixXd predicted(data.samples(), n);
  Data workspace(model);
  Eigen::VectorXd tau(n);
  for (Eigen::Index s = 0; s < data.samples(); ++s) {
    inverse_dynamics(model, workspace, layout, pi, states.q.row(s).transpose(), states.qd.row(s).transpose(),
                     states.qdd.row(s).transpose(), tau);
    predicted.row(s) = tau.transpose();
  }
  TorqueScore score = judge_torque(data.t, data.tau, predicted, joints, judge);
  TorquePrediction prediction;
  prediction.judge = judge;
  if (joints.empty()) {
    for (int k = 0; k < n; ++k) prediction.joints.push_back(k);
  } else {
    prediction.joints = joints;
  }
  prediction.t = std::move(score.t);
  prediction.measured = std::move(score.measured);
  prediction.model = std::move(score.predicted);
  prediction.rms_error = std::move(score.rms_error);
  prediction.relative_error = std::move(score.relative_error);
  prediction.overall_relative_error = score.overall_relative_error;
  return prediction;
}

TorquePrediction combine(const std::vector<TorquePrediction>& predictions) {
  if (predictions.size() == 1) return predictions.front();
  TorquePrediction combined;
  if (predictions.empty()) return combined;
  combined.judge = predictions.front().judge;
  combined.joints = predictions.front().joints;
  Eigen::Index instants = 0;
  for (const TorquePrediction& prediction : predictions) instants += prediction.t.size();
  const Eigen::Index J = predictions.front().measured.cols();
  combined.t.resize(instants);
  combined.measured.resize(instants, J);
  combined.model.resize(instants, J);
  Eigen::Index at = 0;
  for (const TorquePrediction& prediction : predictions) {
    const Eigen::Index count = prediction.t.size();
    combined.t.segment(at, count) = prediction.t;
    combined.measured.middleRows(at, count) = prediction.measured;
    combined.model.middleRows(at, count) = prediction.model;
    at += count;
  }
  const Eigen::MatrixXd error = combined.model - combined.measured;
  combined.rms_error = (error.colwise().squaredNorm() / static_cast<double>(std::max<Eigen::Index>(instants, 1))).cwiseSqrt().transpose();
  combined.relative_error.resize(J);
  for (Eigen::Index j = 0; j < J; ++j) {
    const double norm = combined.measured.col(j).norm();
    combined.relative_error[j] = norm > 0 ? error.col(j).norm() / norm : std::numeric_limits<double>::quiet_NaN();
  }
  const double total = combined.measured.norm();
  combined.overall_relative_error = total > 0 ? error.norm() / total : std::numeric_limits<double>::quiet_NaN();
  return combined;
}

}  // namespace manipid::robot

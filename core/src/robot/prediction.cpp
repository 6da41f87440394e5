// prediction.cpp — inverse dynamics on the judge's states, judged (robot/prediction.h).
#include "manipid/core/robot/prediction.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/rnea.h"

#include <string>
#include <utility>

namespace manipid::robot {

namespace {

TorquePrediction prediction_of(const JudgeOptions& judge, const std::vector<int>& joints, TorqueScore score) {
  TorquePrediction prediction;
  prediction.judge = judge;
  prediction.joints = joints;
  prediction.t = std::move(score.t);
  prediction.measured = std::move(score.measured);
  prediction.model = std::move(score.predicted);
  prediction.rms_error = std::move(score.rms_error);
  prediction.relative_error = std::move(score.relative_error);
  prediction.overall_relative_error = score.overall_relative_error;
  return prediction;
}

}  // namespace

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
  std::vector<int> judged = joints;
  if (judged.empty()) {
    for (int k = 0; k < n; ++k) judged.push_back(k);
  }
  return prediction_of(judge, judged, judge_torque(data.t, data.tau, predicted, judged, judge));
}


TorquePrediction combine(const std::vector<TorquePrediction>& predictions) {
  if (predictions.size() == 1) return predictions.front();
  if (predictions.empty()) return {};
  Eigen::Index instants = 0;
  for (const TorquePrediction& prediction : predictions) instants += prediction.t.size();
  const Eigen::Index J = predictions.front().measured.cols();
  Eigen::VectorXd t(instants);
  Eigen::MatrixXd measured(instants, J), model(instants, J);
  Eigen::Index at = 0;
  for (const TorquePrediction& prediction : predictions) {
    const Eigen::Index count = prediction.t.size();
    t.segment(at, count) = prediction.t;
    measured.middleRows(at, count) = prediction.measured;
    model.middleRows(at, count) = prediction.model;
    at += count;
  }
  return prediction_of(predictions.front().judge, predictions.front().joints,
                       score_judged(std::move(t), std::move(measured), std::move(model)));
}

}  // namespace manipid::robot

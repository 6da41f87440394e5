// joint_weighting.cpp — the per-joint weights of a first fit's residual (estimation/joint_weighting.h).
#include "manipid/core/estimation/joint_weighting.h"

#include <algorithm>

namespace manipid::estimation {

Eigen::VectorXd joint_residual_rms(const Eigen::VectorXd& residual, Eigen::Index joints) {
  Eigen::VectorXd rms = Eigen::VectorXd::Zero(joints);
  const Eigen::Index instants = residual.size() / std::max<Eigen::Index>(joints, 1);
  for (Eigen::Index r = 0; r < residual.size(); ++r) rms[r % joints] += residual[r] * residual[r];
  return (rms / static_cast<double>(std::max<Eigen::Index>(instants, 1))).cwiseSqrt();
}

Eigen::VectorXd per_joint_weights(const Eigen::VectorXd& residual, Eigen::Index joints) {
  const Eigen::VectorXd rms = joint_residual_rms(residual, joints);
  Eigen::VectorXd weights(joints);
  for (Eigen::Index k = 0; k < joints; ++k) weights[k] = rms[k] > 0 ? 1.0 / rms[k] : 1.0;
  return weights / weights.maxCoeff();
}

Eigen::VectorXd row_weights(const Eigen::VectorXd& joint_weights, Eigen::Index rows) {
  const Eigen::Index J = joint_weights.size();
  Eigen::VectorXd weights(rows);
  for (Eigen::Index r = 0; r < rows; ++r) weights[r] = joint_weights[r % J];
  return weights;
}

}  // namespace manipid::estimation

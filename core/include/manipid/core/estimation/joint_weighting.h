// joint_weighting.h — how the joints' torque errors are weighed against each other, for both families.
#pragma once

#include <Eigen/Core>

namespace manipid::estimation {

/// Each family offers unit and one of the others (the paper's model: inverse_variance; a URDF robot:
/// per_joint) and refuses the third with InputError("weights").
enum class JointWeighting {
  unit,              ///< every joint's squared torque error counts alike (the paper)
  inverse_variance,  ///< each joint divided by the variance of its filtered torque (before the fit)
  per_joint,         ///< each joint divided by its residual variance from a first, unweighted fit
};

/// Each joint's RMS over `residual`, whose rows are joint-major within each instant (row r is joint r % joints).
Eigen::VectorXd joint_residual_rms(const Eigen::VectorXd& residual, Eigen::Index joints);
/// per_joint's weights from a first fit's residual: 1/RMS per joint (1 for a joint without residual), scaled so
/// the largest is 1 (costs stay in the torque's units).
Eigen::VectorXd per_joint_weights(const Eigen::VectorXd& residual, Eigen::Index joints);
/// The weight of each of `rows` joint-major rows.
Eigen::VectorXd row_weights(const Eigen::VectorXd& joint_weights, Eigen::Index rows);

}  // namespace manipid::estimation

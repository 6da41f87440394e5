// joint_weighting.h — how the joints' torque errors are weighed against each other, for both families.
#pragma once

namespace manipid::estimation {

/// Each family offers unit and one of the others (the paper's model: inverse_variance; a URDF robot:
/// per_joint) and refuses the third with InputError("weights").
enum class JointWeighting {
  unit,              ///< every joint's squared torque error counts alike (the paper)
  inverse_variance,  ///< each joint divided by the variance of its filtered torque (before the fit)
  per_joint,         ///< each joint divided by its residual variance from a first, unweighted fit
};

}  // namespace manipid::estimation

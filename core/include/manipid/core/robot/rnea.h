// rnea.h — inverse dynamics of a robot Model by recursive Newton–Euler, in the standard parameters.
//
//     τ = M(q) q̈ + C(q, q̇) q̇ + g(q) + τ_f(q̇, q̈)
//
// The rigid-body part comes from each body's 10 standard parameters (mass, first moment, inertia about
// the body's origin: robot/parameters.h), so the same π that identification estimates drives it; τ_f
// is the friction and armature blocks the layout has. Newton–Euler in each body's own frame about its
// origin (Luh, Walker & Paul), 3-D vectors and 3 × 3 rotations, O(n), no allocation: the workspace is the
// Data.
//
// Units: q rad (m prismatic), q̇ rad/s (m/s), q̈ rad/s² (m/s²), τ N·m (N); vectors have n entries.
#pragma once

#include "manipid/core/robot/data.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"

#include <Eigen/Core>

namespace manipid::robot {

/// τ(q, q̇, q̈) with the standard parameters π (dim layout.size(n), robot/parameters.h), written to `tau`
/// (n). Leaves each body's kinematics and the joint wrenches in `data` (robot/data.h). Throws InputError
/// when a size does not match the model.
void inverse_dynamics(const Model& model, Data& data, const ParameterLayout& layout,
                      const Eigen::Ref<const Eigen::VectorXd>& pi, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& qdd,
                      Eigen::Ref<Eigen::VectorXd> tau);
/// The same, allocating its workspace and result: for tests and one-off calls.
Eigen::VectorXd inverse_dynamics(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi,
                                 const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd);

/// sign(x) for Coulomb friction: −1, 0 or +1, and sign(0) = sign(−0) = 0 (std::copysign(1, 0) is +1).
/// NaN gives 0.
inline double friction_sign(double x) { return static_cast<double>((x > 0.0) - (x < 0.0)); }

}  // namespace manipid::robot

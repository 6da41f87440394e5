// regressor.h — the torque as a linear function of the standard parameters, τ = Y(q, q̇, q̈) · π.
//
// Y is n × dim π (robot/parameters.h gives π's order and names). Column block k of body k holds the
// Newton–Euler wrench of a body moving as body k per unit of each standard parameter, carried back to
// every joint j ≤ k and projected on its axis; Y(j, block k) = 0 for k < j (a body never loads the joints
// beyond it). The friction blocks are diagonal: q̇_k, sign(q̇_k) (sign(0) = 0), 1, q̈_k.
// For every π, Y · π equals inverse_dynamics (robot/rnea.h) with that π.
//
// Identification stacks N samples: stacked_regressor() fills (N·n) × dim π, sample-major — row s·n + k−1
// is joint k at sample s — reusing one Data and allocating nothing.
#pragma once

#include "manipid/core/robot/data.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"

#include <Eigen/Core>

namespace manipid::robot {

/// Y(q, q̇, q̈) into `Y` (n × layout.size(n); a block of a larger matrix is fine). Leaves the kinematics
/// in `data` (its wrench fields are not touched). Throws InputError when a size does not match the model.
void regressor(const Model& model, Data& data, const ParameterLayout& layout,
               const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
               const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y);
/// The same, allocating its workspace and result.
Eigen::MatrixXd regressor(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& q,
                          const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd);

/// Y for N samples at once. q, qd, qdd are n × N (one column per sample, as the rest of manipid stores
/// trajectories); `Y` is (N·n) × layout.size(n), sample-major: rows s·n .. s·n + n − 1 are regressor() at
/// sample s. Throws InputError when a size does not match.
void stacked_regressor(const Model& model, Data& data, const ParameterLayout& layout,
                       const Eigen::Ref<const Eigen::MatrixXd>& q, const Eigen::Ref<const Eigen::MatrixXd>& qd,
                       const Eigen::Ref<const Eigen::MatrixXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y);
Eigen::MatrixXd stacked_regressor(const Model& model, const ParameterLayout& layout, const Eigen::MatrixXd& q,
                                  const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qdd);

}  // namespace manipid::robot

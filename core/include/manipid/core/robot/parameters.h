// parameters.h — the standard parameter vector π of a robot: its layout, names and the URDF's own values.
//
// π is what identification estimates; the torque is linear in it, τ = Y(q, q̇, q̈) · π (robot/regressor.h).
// Its order, for a robot with n moving joints:
//
//     [ m1 mx1 my1 mz1 Ixx1 Ixy1 Ixz1 Iyy1 Iyz1 Izz1 | ... | the same for body n ]   10 per body
//     [ fv1 .. fvn ]   viscous friction    τ_k += fv_k · q̇_k                (if layout.viscous)
//     [ fc1 .. fcn ]   Coulomb friction    τ_k += fc_k · sign(q̇_k), sign(0) = 0 (if layout.coulomb)
//     [ fo1 .. fon ]   offset              τ_k += fo_k                      (if layout.offset)
//     [ Ia1 .. Ian ]   armature            τ_k += Ia_k · q̈_k                (if layout.armature)
//
// Body k's block is InertialParameters::vector(): mass (kg), first moment m·c (kg·m) and the inertia
// tensor's entries about body k's origin (kg·m²), all in body k's frame (robot/model.h). Friction blocks
// are grouped by kind, so each one is a diagonal n × n block of Y (diag q̇, diag sign q̇, identity, diag q̈)
// and a whole kind can be switched off by the layout. Units of the friction terms follow the joint:
// N·m·s/rad, N·m, N·m, kg·m² for revolute joints; N·s/m, N, N, kg for prismatic ones.
//
// The armature Ia_k is a rotor inertia seen through the gearbox (reflected inertia): it adds Ia_k q̈_k to
// τ_k only, like KDL's joint inertia; the rotor's gyroscopic coupling to the links is not modelled.
#pragma once

#include "manipid/core/robot/model.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace manipid::robot {

/// Inertial parameters per body in π.
inline constexpr int kInertialParametersPerBody = 10;

/// Which friction and armature blocks π has (each block: one value per joint). Defaults: viscous and
/// Coulomb, the terms a URDF's <dynamics damping friction> carries and every real arm needs; offset and
/// armature are opt-in (an offset absorbs a torque sensor's bias, armature a geared motor's rotor).
struct ParameterLayout {
  bool viscous = true;    ///< fv_k
  bool coulomb = true;    ///< fc_k
  bool offset = false;    ///< fo_k
  bool armature = false;  ///< Ia_k

  /// dim π for a robot of `joint_count` moving joints.
  int size(int joint_count) const;
  /// First index in π of each block, or −1 when the layout has no such block.
  int viscous_begin(int joint_count) const;
  int coulomb_begin(int joint_count) const;
  int offset_begin(int joint_count) const;
  int armature_begin(int joint_count) const;
};

/// Names in π order: m1 mx1 my1 mz1 Ixx1 Ixy1 Ixz1 Iyy1 Iyz1 Izz1 ... fv1..fvn fc1..fcn fo1..fon Ia1..Ian.
/// Index k is the k-th moving joint from the base: model.joints[k−1] names its URDF joint and link.
std::vector<std::string> standard_parameter_names(int joint_count, const ParameterLayout& layout);
std::vector<std::string> standard_parameter_names(const Model& model, const ParameterLayout& layout);

/// The model's own π (for a URDF, the CAD prior): each body's merged inertial parameters, fv and fc from
/// the URDF's <dynamics damping friction>, fo = 0, Ia = 0.
Eigen::VectorXd standard_parameters(const Model& model, const ParameterLayout& layout);

}  // namespace manipid::robot

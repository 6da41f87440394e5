// payload.h — a payload's (tool's, load's) 10 inertial parameters from one run of an identified arm, by the torque the arm leaves unexplained.
//
// A payload rigidly fixed to the tip link adds its inertial parameters to body n's (robot/model.h):
//
//     τ = Y(q, q̇, q̈) (π_arm + E π_B),   π_B = T π_P
//
// with E placing body n's 10 entries in π, π_P the payload's parameters in the tip link's frame about its
// origin, and T the linear map to body n's frame (InertialParameters::expressed_in with the tip's pose in
// body n, Model::tip_placement). So the residual the arm leaves, r = τ − Y π_arm, is linear in π_P:
//
//     L r = (L Y_n T) π_P
//
// The steps:
//   1. prepare the run as an arm's identification does (trim, uniform grid; signal/resample.h);
//   2. filter as the arm's identification does (robot/filtered_regressor.h): D gives the states, the
//      regressor is formed on the working grid, the arm's torque Y π_arm is subtracted from τ there, and L
//      passes the residual and body n's 10 columns alike (parallel filtering), at L's cut-off or at each
//      candidate (candidate_cutoffs());
//   3a. choose L's cut-off by held-out evidence, as an arm's identification does (robot/identification.h's
//      step 3): each candidate's fit on four fifths of every run predicts the fifth it did not see, against
//      one target for all — the arm's residual through the judge's low-pass;
//   3b. solve by the one linear least-squares rule (estimation/linear_least_squares.h) with the prior 0 (no
//      payload): a direction the run does not excite stays at 0 and is named, never filled with noise; a
//      known mass or centre of mass is moved to the right-hand side (or into a combined column) first; with
//      per_joint weighting, each joint's rows are divided by its residual RMS from a first solve;
//   4. report in the units a tool is mounted with: mass (kg), centre of mass (m, tip-link frame), inertia
//      about the centre of mass in tip-link axes (kg·m², URDF tensor entries), each with its standard error
//      (σ² of the filtered residual corrected as estimation::filtered_residual_factor says, inflated when a
//      jackknife over blocks of time finds the residual correlated — a real arm's model error is; the delta
//      method through c = h/m and I_c = I_O − (‖h‖² E − h hᵀ)/m), and the training rows' error without and
//      with it;
//   5. with `physical`, the same least squares over real rigid bodies only (mass > 0, inertia about the centre
//      of mass positive definite, triangle inequalities): robot/consistent_fit.h's fit of one link, a known
//      mass or centre of mass held by rows that outweigh the data's strongest direction a thousandfold.
// The arm may be any standard vector whose torque is right: a URDF's values, or manipid's own identification
// (IdentificationResult::point), whose base parameters need not be physically consistent.
#pragma once

#include "manipid/core/estimation/joint_weighting.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/robot/prediction.h"
#include "manipid/core/signal/judge.h"
#include "manipid/core/signal/resample.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <array>
#include <atomic>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace manipid::robot {

/// The arm the payload is mounted on: its standard vector and its layout (friction, armature).
struct ArmParameters {
  ParameterLayout layout;
  Eigen::VectorXd pi;  ///< dim layout.size(n): a URDF's values or an identification's `point`
};

struct PayloadOptions {
  /// Trim and uniform grid (resample.h).
  DataPreparation preparation;
  /// The judge: its cut-off is the comparison low-pass L's unless `comparison_cutoff_hz` is given, and its
  /// trim the rows' (robot/filtered_regressor.h).
  JudgeOptions judge;
  /// L's cut-off, Hz; 0 = chosen by held-out evidence among candidate_cutoffs() (step 3a).
  double comparison_cutoff_hz = 0.0;
  /// Joints (0-based) whose torque is fitted; empty = all.
  std::vector<int> torque_joints;
  /// unit, or per_joint: each joint's rows divided by its residual RMS from a first, unweighted solve (as an
  /// arm's identification offers; inverse_variance is refused with InputError("weights")).
  estimation::JointWeighting weighting = estimation::JointWeighting::unit;
  /// Known mass, kg (a scale): only the rest is estimated.
  std::optional<double> known_mass;
  /// Known centre of mass in the tip link's frame, m: only the rest is estimated.
  std::optional<Eigen::Vector3d> known_centre_of_mass;
  /// Make the payload a real rigid body (step 5): when the least-squares values are one already, nothing
  /// changes; otherwise the nearest fit that is one. Only for a payload the run detects (a run without one
  /// keeps the least-squares answer, ≈ 0 kg, and says so).
  bool physical = false;
  /// Checked per run while the rows are built; identify_payload() returns with `cancelled` set.
  const std::atomic<bool>* cancel = nullptr;
};

/// The six entries of a symmetric 3 × 3 tensor in URDF order: ixx, ixy, ixz, iyy, iyz, izz.
using TensorEntries = std::array<double, 6>;

struct PayloadResult {
  /// The payload in the tip link's frame about its origin: (m, mx, my, mz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz),
  /// kg, kg·m, kg·m² (robot/parameters.h's order for one body), and their standard errors (0 for a value
  /// given, NaN for one the run does not determine).
  Eigen::Matrix<double, 10, 1> estimate = Eigen::Matrix<double, 10, 1>::Zero();
  Eigen::Matrix<double, 10, 1> std_errors = Eigen::Matrix<double, 10, 1>::Zero();
  /// Of each of the 10: the share of its estimate the run determines (1: the data alone; 0: stays at 0).
  Eigen::Matrix<double, 10, 1> data_share = Eigen::Matrix<double, 10, 1>::Zero();
  static const std::array<const char*, 10>& names();  ///< m, mx, my, mz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz

  double mass = 0.0;                                          ///< kg
  double mass_std_error = 0.0;                                ///< kg
  /// m, tip-link frame; NaN when the mass is not distinguishable from 0 (no payload) or not determined.
  Eigen::Vector3d centre_of_mass = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Vector3d centre_of_mass_std_errors = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  /// About the centre of mass, tip-link axes, kg·m² (NaN as the centre of mass).
  TensorEntries inertia{};
  TensorEntries inertia_std_errors{};
  /// The payload is a real mass: m > 2 standard errors (a run without one answers ≈ 0 ± its uncertainty).
  bool detected = false;
  /// Parameters (names()) the run does not determine (data share < 1/2): they stay at 0, and each is named in
  /// `warnings` with what motion would determine it.
  std::vector<std::string> undetermined;

  std::vector<int> torque_joints;   ///< the joints fitted (0-based)
  Eigen::VectorXd joint_weights;    ///< per fitted joint (all 1 with unit weighting; the largest 1 with per_joint)
  int rows = 0;                     ///< least-squares rows
  double comparison_cutoff_hz = 0;  ///< L's cut-off as used (given or chosen), Hz
  /// Step 3a's candidates, each with its held-out error: the relative RMS of its held-out predictions of the
  /// arm's residual (the judge's low-pass of it); empty when the cut-off was given.
  struct CutoffCandidate {
    double cutoff_hz = 0.0;
    double held_out_error = 0.0;
  };
  std::vector<CutoffCandidate> candidates;
  double held_out_error = std::numeric_limits<double>::quiet_NaN();  ///< the chosen candidate's (NaN: given)
  /// The training rows' filtered torque error relative to the filtered torque, ‖L r‖ / ‖L τ‖ with the arm
  /// alone and ‖L r − W π̂_P‖ / ‖L τ‖ with the payload.
  double arm_only_error = 0.0;
  double with_payload_error = 0.0;
  double residual_variance = 0.0;   ///< σ² of one filtered residual (N·m)², as corrected
  /// The factor the standard errors' variances were multiplied by because the residual is not white: a
  /// delete-one-block jackknife over 10 spans of time against the formula (≥ 1; ≈ 1 on white noise).
  double variance_inflation = 1.0;
  /// The estimate is a real rigid body (check_link: m > 0, I_c positive definite, triangle inequalities).
  bool consistent = false;
  /// What makes it not one, in words (empty when consistent).
  std::vector<std::string> consistency_findings;
  /// Step 5, when it ran (options.physical and a payload detected).
  struct PhysicalFit {
    bool least_squares_consistent = false;  ///< the least-squares values were a real body already: unchanged
    std::vector<std::string> least_squares_findings;  ///< what made them not one
    /// ‖L r − W π̂‖² at the physical estimate over that at the least-squares one, minus 1 (≥ 0): what being a
    /// real body costs the fit.
    double relative_cost_increase = 0.0;
    std::string report;  ///< the fit's one line (ConsistentFitSummary::brief_report)
  };
  std::optional<PhysicalFit> physical;
  std::vector<std::string> warnings;
  double wall_seconds = 0.0;
  bool cancelled = false;
};

/// Identifies the payload on the tip link of `model` (with the arm `arm`) from runs with the payload fixed to
/// it (q and τ; any time stamps). Throws InputError for unusable input (joint counts, no torque, a wrong-size
/// or non-finite arm vector, a known mass ≤ 0, runs too short for the filters).
PayloadResult identify_payload(const Model& model, const ArmParameters& arm, const std::vector<Trajectory>& runs,
                               const PayloadOptions& options);

/// T: the last body's ten parameters (its frame) from a payload's on the tip link (the tip link's frame, about
/// its origin), π_B = T π_P — linear (InertialParameters::expressed_in with Model::tip_placement). The payload's
/// regressor columns are the last body's times T.
Eigen::Matrix<double, 10, 10> payload_to_last_body(const Model& model);

/// The arm's standard vector with the payload added to body n (its tip-link parameters moved into body n's
/// frame): what predicts the arm carrying it.
Eigen::VectorXd with_payload(const Model& model, const ArmParameters& arm, const Eigen::Matrix<double, 10, 1>& payload);

/// How the arm predicts runs with the payload, without it and with it, under the judge (robot/prediction.h;
/// runs combined, each prepared as `preparation` says).
struct PayloadValidation {
  TorquePrediction arm_only;
  TorquePrediction with_payload;
};
PayloadValidation validate_payload(const Model& model, const ArmParameters& arm, const PayloadResult& payload,
                                   const std::vector<Trajectory>& runs, const PayloadOptions& options);

}  // namespace manipid::robot

// identification.h — a rigid-body robot's base parameters from measured q and τ, by the paper's
// input-error method, which is linear here: one least-squares solve, no iterative optimiser.
//
// The steps (each its own header):
//   1. prepare the data: trim the ramps, drop stale repeated rows, resample onto a uniform grid
//      (resample.h);
//   2. filter: q^f, q̇^f, q̈^f from the differential filters, Y(q^f, q̇^f, q̈^f), then L Y beside L τ —
//      both sides through the same low-pass (robot/filtered_regressor.h). Chosen from the data unless
//      given: the motion's band f_m — the frequency below which all but 1e-6 of the power of the
//      detrended angles lies — then differentiation band Ωg = 100·Ω_m (the differentiators exact to
//      ~1e-5 on the motion; at most π/2) with M = ⌈6.4π/Ωg⌉ (the paper's M = 100, Ωg = 0.2 proportion),
//      and comparison band Ω_c = 5·Ω_m (the torque the motion makes, its nonlinear harmonics included;
//      not the noise) with M_c = ⌈4π/Ω_c⌉ (its passband need not be flat: both sides go through it),
//      shortened — the band widened — if the filters would consume more than a third of the data;
//   3. solve (L Y_b) β = L τ for the base parameters β (robot/base_parameters.h) by QR on column-scaled
//      rows, optionally weighting each joint by its residual variance; directions the data do not excite
//      (relative singular value < 1e-10) stay at the prior's value and a warning names them;
//   4. report: standard errors σ²(W_bᵀW_b)⁻¹ with σ² from the residual, corrected for the filter's
//      correlation (white noise through L keeps Σc² of its variance, and rows D apart are not
//      independent: factor 1/(D Σc²), never below 1), correlations, the scaled regressor's condition
//      number, the standard parameters no data can determine, and `point`: the full standard vector with
//      the estimated base parameters that is nearest (Euclidean) to the prior — the URDF's own values —
//      so what the data cannot see stays at the CAD values;
//   5. physical consistency (robot/consistency.h): whether each link of `point` is a real body (mass > 0,
//      pseudo-inertia positive definite: inertia about the centre of mass positive definite, triangle
//      inequalities) and each fv, fc, Ia ≥ 0. With `physical`, the constrained fit (robot/consistent_fit.h:
//      log-Cholesky coordinates per link, Levenberg–Marquardt on the same rows, from the projected
//      least-squares point) replaces `point` and the base estimates, and reports the cost it adds.
#pragma once

#include "manipid/core/signal/filters.h"
#include "manipid/core/signal/resample.h"
#include "manipid/core/robot/base_parameters.h"
#include "manipid/core/robot/consistency.h"
#include "manipid/core/robot/consistent_fit.h"
#include "manipid/core/robot/filtered_regressor.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <atomic>
#include <optional>
#include <string>
#include <vector>

namespace manipid::robot {

enum class JointWeighting {
  unit,       ///< every joint's squared torque error counts alike
  per_joint,  ///< each joint divided by its residual variance from a first, unweighted fit
};

struct IdentificationOptions {
  /// Friction and armature terms estimated beside the 10 inertial parameters per body.
  ParameterLayout layout;
  /// Trim and uniform grid (resample.h).
  DataPreparation preparation;
  /// The differentiation filter's half-length M and band Ωg (rad/sample); 0 = chosen from the data (both).
  int half_length = 0;
  double band = 0.0;
  /// The comparison filter's (the low-pass of τ and of the regressor's columns); 0 = chosen (both).
  int comparison_half_length = 0;
  double comparison_band = 0.0;
  JointWeighting weighting = JointWeighting::unit;
  /// A physically consistent estimate (see the file comment, step 5). The standard errors stay the
  /// unconstrained fit's: they describe the data, and they hold while no link sits on the boundary.
  bool physical = false;
  /// The prior standard vector (the CAD values; dim layout.size(n)); empty = the model's own
  /// (standard_parameters(model, layout)).
  Eigen::VectorXd prior;
  BaseParameterOptions base;
  /// Checked while the rows are built; when it becomes true identify() returns with `cancelled` set.
  const std::atomic<bool>* cancel = nullptr;
};

struct IdentificationResult {
  std::vector<std::string> standard_names;  ///< π's names, robot/parameters.h
  Eigen::VectorXd prior;                    ///< the prior π (the URDF's values unless given)
  BaseParameters base;                      ///< names and combinations of the base parameters
  Eigen::VectorXd estimate;                 ///< β̂, base order
  Eigen::VectorXd std_errors;               ///< of β̂; NaN for a direction the data do not excite
  Eigen::MatrixXd correlation;              ///< of β̂
  /// σ_max/σ_min of the column-scaled base regressor the data gave (excitation quality; ∞ when some base
  /// direction is not excited).
  double condition_number = 0.0;
  /// Base parameters (names) the data barely or do not excite (relative singular value < 1e-10): their
  /// estimates are the prior's.
  std::vector<std::string> unexcited;
  /// The full standard vector: estimated base parameters, nearest to the prior.
  Eigen::VectorXd point;
  /// Standard parameters that never enter the torque (the base parameter names list the rest).
  std::vector<std::string> unidentifiable;
  /// Whether `point` is physically consistent, link by link (robot/consistency.h).
  ConsistencyReport consistency;
  /// With IdentificationOptions::physical: the constrained fit's summary (what it cost, why it stopped).
  std::optional<ConsistentFitSummary> physical;

  FilterPair filters;
  bool filters_chosen_automatically = false;
  double motion_band_hz = 0.0;       ///< f_m found in the data (0 when both filters were given)
  int decimation = 1;
  int rows = 0;                      ///< least-squares rows (instants × joints)
  Eigen::VectorXd residual_rms;      ///< per joint, N·m, of L τ − (L Y_b) β̂
  Eigen::VectorXd joint_weights;     ///< per joint, as used (1 for unit weighting)
  double residual_variance = 0.0;    ///< σ² of one (unweighted) filtered residual
  std::vector<std::string> warnings;
  double wall_seconds = 0.0;
  bool cancelled = false;
};

/// How well a model predicts a second run: the estimate beside the prior (the URDF's own values), both
/// through the identification's filters (robot/filtered_regressor.h).
struct ValidationReport {
  TorquePrediction estimate;  ///< with IdentificationResult::point
  TorquePrediction prior;     ///< with IdentificationResult::prior
  std::vector<std::string> warnings;  ///< e.g. the second run's resampling
};

/// Predicts `data`'s torque (any time stamps; trimmed and resampled as `preparation` says, onto the
/// identification's sample period) with the estimate and with the prior.
ValidationReport validate(const Model& model, const ParameterLayout& layout, const IdentificationResult& result,
                          const Trajectory& data, const DataPreparation& preparation);

/// Identifies the base parameters of `model` from `data` (with tau columns; any time stamps). Throws
/// InputError for unusable input (joint counts, no torque, too short for the filter, a bad prior).
IdentificationResult identify(const Model& model, const Trajectory& data, const IdentificationOptions& options);

/// Where the links and the non-negative entries (fv, fc, Ia) are in π of `layout`, with their names: what
/// check_consistency() and fit_consistent() (robot/consistency.h, robot/consistent_fit.h) need to know.
ParameterStructure parameter_structure(const Model& model, const ParameterLayout& layout);

/// The motion's band f_m, Hz: the frequency below which all but `tail` of the power of the angles lies
/// (each joint detrended by its end-point line, Hann window, zero-padded FFT; joints summed). Uniform data.
double motion_band(const Trajectory& data, double tail = 1e-6);

/// The filters identify() uses for uniform `data` when none are given (see the file comment).
FilterPair choose_filters(const Trajectory& data);

}  // namespace manipid::robot

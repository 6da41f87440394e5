// identification.h — a rigid-body robot's base parameters from measured q and τ, by the paper's
// input-error method, which is linear here: least squares on filtered rows, no iterative optimiser.
//
// The steps:
//   1. prepare each run alone: trim the ramps, drop stale repeated rows, resample onto a uniform grid
//      (signal/resample.h) — every run onto the first run's period. The joints whose torque is measured:
//      those given, else every joint whose τ is not zero throughout (a joint logged as ≈ 0 N·m while it
//      moves has no sensor: its rows would pull its link toward zero, so they are left out, with a warning);
//   2. filter: the differentiation filter D gives q^f, q̇^f, q̈^f; Y(q^f, q̇^f, q̈^f) and τ both pass the
//      comparison low-pass L (robot/filtered_regressor.h), each run alone, rows stacked;
//   3. choose by held-out evidence (estimation/cross_validation.h): each candidate comparison cut-off
//      (candidate_cutoffs(): kCutoffFactors × the judge's cut-off, or the one given; filtered_regressor.h), each relative ridge toward the prior
//      (estimation::default_ridges(), or the one given) and, with `friction_auto`, each friction model
//      (none, viscous, viscous + Coulomb, viscous + Coulomb + offset) is fitted on four fifths of every run
//      and scored on the fifth it did not see, five times over, against one common target — the judge's
//      low-pass of the measured torque (signal/judge.h) — so no candidate wins by changing what it is
//      judged on. The lowest held-out error wins;
//   4. solve (L Y_b) β = L τ for the base parameters β (robot/base_parameters.h) by the one linear
//      least-squares rule (estimation/linear_least_squares.h): columns scaled to unit norm, negligible
//      columns and directions the data do not determine (estimation/rules.h) kept at the prior (the
//      URDF's values), the rest shrunk toward it by the chosen ridge; optionally each joint weighted by its
//      residual variance;
//   5. report: standard errors σ² · cov with σ² from the residual corrected for the filter's correlation
//      (estimation::filtered_residual_factor), correlations, the scaled regressor's condition number, each
//      base parameter's data share (how much of its estimate the data determine rather than the prior),
//      the base parameters the data barely see (`unexcited`, share < 1/2), warnings naming every estimate far
//      from its prior, and `point`: the full standard vector with the estimated base parameters that is
//      nearest (Euclidean) to the prior, so what the data cannot see stays at the CAD values; and how `point`
//      predicts the training runs under the judge (`fit`);
//   6. physical consistency (robot/consistency.h): whether each link of `point` is a real body (mass > 0,
//      pseudo-inertia positive definite) and each fv, fc, Ia ≥ 0. With `physical`, the constrained fit
//      (robot/consistent_fit.h) replaces `point` and the base estimates, and reports the cost it adds.
#pragma once

#include "manipid/core/estimation/joint_weighting.h"
#include "manipid/core/robot/base_parameters.h"
#include "manipid/core/robot/consistency.h"
#include "manipid/core/robot/consistent_fit.h"
#include "manipid/core/robot/filtered_regressor.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/robot/prediction.h"
#include "manipid/core/signal/judge.h"
#include "manipid/core/signal/resample.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <atomic>
#include <optional>
#include <string>
#include <vector>

namespace manipid::robot {

/// unit or per_joint (estimation/joint_weighting.h); inverse_variance is the paper's and refused here.
using estimation::JointWeighting;


struct IdentificationOptions {
  /// Friction and armature terms estimated beside the 10 inertial parameters per body.
  ParameterLayout layout;
  /// Choose the friction terms by held-out evidence among none, viscous, viscous + Coulomb and viscous +
  /// Coulomb + offset (step 3); `layout` then only says whether armature is estimated.
  bool friction_auto = false;
  /// Trim and uniform grid (resample.h), for every run.
  DataPreparation preparation;
  /// The comparison low-pass's cut-off, Hz; 0 = chosen (step 3).
  double comparison_cutoff_hz = 0.0;
  /// The differentiation filter's half-length M and band Ωg (rad/sample); 0 = by the rule of
  /// differentiation_for() (both). Give both or neither.
  int half_length = 0;
  double band = 0.0;
  /// The relative ridge toward the prior (estimation/linear_least_squares.h); < 0 = chosen (step 3).
  double ridge = -1.0;
  /// The judge: the common target of step 3, and what `validate()` and the fit's figures are judged under.
  JudgeOptions judge;
  /// Joints (0-based) whose torque is measured and fitted; empty = every joint whose τ is not ≈ 0 (step 1).
  std::vector<int> torque_joints;
  JointWeighting weighting = JointWeighting::unit;
  /// A physically consistent estimate (step 6). The standard errors stay the unconstrained fit's: they
  /// describe the data, and they hold while no link sits on the boundary.
  bool physical = false;
  /// The prior standard vector (the CAD values; dim layout.size(n)); empty = the model's own
  /// (standard_parameters(model, layout)).
  Eigen::VectorXd prior;
  BaseParameterOptions base;
  /// Checked while the rows are built, per base-parameter column, per candidate and in the physical fit; when
  /// it becomes true identify() returns with `cancelled` set (and nothing else).
  const std::atomic<bool>* cancel = nullptr;
};

/// One candidate of step 3 and what it scored.
struct CandidateScore {
  double cutoff_hz = 0.0;         ///< the comparison low-pass
  std::string friction;           ///< the friction terms, e.g. "viscous,coulomb,offset" ("none")
  double ridge = 0.0;             ///< its best ridge
  double held_out_error = 0.0;    ///< relative RMS of its held-out predictions against the judge's target
};

struct IdentificationResult {
  std::vector<std::string> standard_names;  ///< π's names, robot/parameters.h
  ParameterLayout layout;                   ///< the friction terms estimated (chosen with friction_auto)
  Eigen::VectorXd prior;                    ///< the prior π (the URDF's values unless given)
  BaseParameters base;                      ///< names and combinations of the base parameters
  Eigen::VectorXd estimate;                 ///< β̂, base order
  Eigen::VectorXd std_errors;               ///< of β̂; NaN where the data do not determine it
  Eigen::VectorXd data_share;               ///< of β̂: 1 = the data alone, 0 = the prior alone
  Eigen::MatrixXd correlation;              ///< of β̂
  /// σ_max/σ_min of the column-scaled base regressor the data gave (excitation quality; ∞ when some
  /// base direction is not determined).
  double condition_number = 0.0;
  /// Base parameters (names) the data barely see (data share < 1/2): their estimates are mostly the prior's.
  std::vector<std::string> unexcited;
  /// The full standard vector: estimated base parameters, nearest to the prior.
  Eigen::VectorXd point;
  /// Standard parameters that never enter the torque (the base parameter names list the rest).
  std::vector<std::string> unidentifiable;
  /// Whether `point` is physically consistent, link by link (robot/consistency.h).
  ConsistencyReport consistency;
  /// With IdentificationOptions::physical: the constrained fit's summary (what it cost, why it stopped).
  std::optional<ConsistentFitSummary> physical;

  FilterPair filters;                  ///< D and L as used
  double ridge = 0.0;                  ///< the relative ridge used
  bool chosen_by_held_out = false;     ///< step 3 chose the cut-off, the ridge or the friction terms
  std::vector<CandidateScore> candidates;  ///< step 3's scores (empty when nothing was chosen)
  double held_out_error = 0.0;         ///< the chosen candidate's (NaN when nothing was chosen)
  JudgeOptions judge;                  ///< the judge's low-pass
  std::vector<int> torque_joints;      ///< the joints fitted (0-based)
  int runs = 1;                        ///< training runs
  int rows = 0;                        ///< least-squares rows (instants × fitted joints, all runs)
  Eigen::VectorXd residual_rms;        ///< per fitted joint, N·m, of L τ − (L Y_b) β̂
  /// The training runs predicted with `point`, under the judge (robot/prediction.h; runs combined).
  TorquePrediction fit;
  Eigen::VectorXd joint_weights;       ///< per fitted joint, as used (1 for unit weighting)
  double residual_variance = 0.0;      ///< σ² of one (unweighted) filtered residual
  std::vector<std::string> warnings;
  double wall_seconds = 0.0;
  bool cancelled = false;
};

/// How well a model predicts runs it was not fitted on: the estimate beside the prior (the URDF's own
/// values), both under the identification's judge (robot/prediction.h), over its fitted joints.
struct ValidationReport {
  TorquePrediction estimate;  ///< with IdentificationResult::point
  TorquePrediction prior;     ///< with IdentificationResult::prior
  std::vector<std::string> warnings;  ///< e.g. the run's resampling
};

/// Predicts the runs' torque (any time stamps; each trimmed and resampled as `preparation` says, onto the
/// identification's period) with the estimate and with the prior; several runs are judged each alone and
/// their figures combined (robot/prediction.h, combine()).
ValidationReport validate(const Model& model, const IdentificationResult& result, const std::vector<Trajectory>& runs,
                          const DataPreparation& preparation);

/// Identifies the base parameters of `model` from one or more runs (with tau columns; any time stamps).
/// Throws InputError for unusable input (joint counts, no torque, too short for the filters, a bad prior).
IdentificationResult identify(const Model& model, const std::vector<Trajectory>& runs, const IdentificationOptions& options);
IdentificationResult identify(const Model& model, const Trajectory& data, const IdentificationOptions& options);

/// Where the links and the non-negative entries (fv, fc, Ia) are in π of `layout`, with their names: what
/// check_consistency() and fit_consistent() (robot/consistency.h, robot/consistent_fit.h) need to know.
ParameterStructure parameter_structure(const Model& model, const ParameterLayout& layout);

/// The friction terms of `layout` as text: "viscous,coulomb,offset", "none".
std::string friction_text(const ParameterLayout& layout);

}  // namespace manipid::robot

// identification.h — estimating the model's parameters from measured joint data.
//
// Three methods behind one call, identify():
//
//  input-error (the paper's section 5, default): filter q with the differential filters to
//    get q^f, q̇^f, q̈^f, filter the measured torque to get τ^f, and minimise
//        J(θ) = Σ_joints w_j · mean_samples (τ̂(q^f, q̇^f, q̈^f, θ) − τ^f)²
//    — no ODE solve per iteration. Because τ̂ = Y β(θ) (regressor.h), J is a quadratic form
//    in β whose matrices are accumulated once, so each evaluation costs O(dim β²).
//  output-error: simulate the closed loop for each candidate θ with the recorded reference
//    and the controller gains, and minimise the mismatch of simulated and measured q.
//  two-stage: input-error for a fast start, then a few Gauss–Newton output-error iterations.
//    Input-error on noisy data is biased (noise in q̈^f enters the regressor); output-error
//    from a good start removes that bias in a handful of simulations.
//
// The result (IdentificationResult) follows Ceres's Summary: what was estimated, how well
// (standard errors, correlations), what the data cannot tell apart (identifiability), and
// why the optimiser stopped.
#pragma once

#include "manipid/core/errors.h"
#include "manipid/core/estimation/history.h"
#include "manipid/core/estimation/joint_weighting.h"
#include "manipid/core/paper/controller_gains.h"
#include "manipid/core/signal/filters.h"
#include "manipid/core/paper/model.h"
#include "manipid/core/signal/resample.h"
#include "manipid/core/paper/simulation.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <algorithm>
#include <atomic>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace manipid {

enum class IdentificationMethod { input_error, output_error, two_stage };
const char* to_string(IdentificationMethod method);
/// "input-error", "output-error" or "two-stage"; throws InputError(field) otherwise.
IdentificationMethod parse_identification_method(const std::string& text, const std::string& field = "method");

/// The algorithms offered: "LM" (Levenberg–Marquardt on the least-squares form, input-error and
/// two-stage's first stage) and the NLopt algorithms by NLopt's names.
std::vector<std::string> identification_algorithms();
/// What `method` runs when no algorithm is named: "LM" for input-error and two-stage, "LN_BOBYQA"
/// for output-error (its cost has no Jacobian short of finite differences of simulations).
std::string default_algorithm(IdentificationMethod method);
/// The algorithm `method` runs: `algorithm`, or the method's default when it is empty. Throws
/// InputError("algorithm") for an unknown name, or one that needs derivatives for output-error.
std::string resolve_algorithm(IdentificationMethod method, const std::string& algorithm);

/// Where the input torque comes from.
enum class TorqueSource {
  automatic,  ///< measured torque when the data has it, else the reference and gains
  measured,   ///< the data's tau columns, low-passed
  reference,  ///< τ = Kp (r − q) − Kd q̇ from the data's ref columns, filtered consistently (the paper)
};

/// unit or inverse_variance (estimation/joint_weighting.h); per_joint is a URDF robot's and refused here.
using estimation::JointWeighting;

struct IdentificationOptions {
  IdentificationMethod method = IdentificationMethod::input_error;
  /// What is done to the data first: ramps trimmed, non-uniform time stamps resampled onto a
  /// uniform grid (with a warning saying so), see resample.h.
  DataPreparation preparation;
  /// Empty (default): the method's, default_algorithm(). "LM": Levenberg–Marquardt on the cost's
  /// least-squares form |R β(θ) − z|² with its exact Jacobian (not for output-error). NLopt's
  /// LN_BOBYQA (the paper's reproduction), LN_NELDERMEAD, LN_SBPLX (derivative-free), LD_LBFGS,
  /// LD_SLSQP (exact gradient).
  std::string algorithm;

  /// Names of the free parameters (m1..mn, l1..ln); empty = all. The rest stay at `initial`.
  std::vector<std::string> free;
  /// Start (and the value of fixed parameters). Required.
  Parameters initial;
  /// Bounds on θ (2n entries, θ order); empty = [0, +∞) for every parameter.
  Eigen::VectorXd lower, upper;

  /// Filter half-length M; 0 = chosen from the data (see `band`).
  int half_length = 0;
  /// Band edge Ωg in rad/sample; 0 = chosen from the data ("auto"): the widest band whose
  /// noise amplification stays below the modelling error, see identification.cpp.
  double band = 0.0;

  TorqueSource torque_source = TorqueSource::automatic;
  JointWeighting weighting = JointWeighting::unit;
  /// Controller gains, used for TorqueSource::reference and by output-error and two-stage:
  /// the gains the user gives (or that a simulation used). When empty and the data carry tau
  /// and ref, the gains are estimated from the data (controller_gains.h, reported in the
  /// result's `estimated_gains`); when empty and the data have no tau, `assumed_controller`
  /// is used with a warning saying so. Given gains that the data contradict are used as given,
  /// with a warning naming the joint and the gains the data suggest.
  std::optional<PdController> controller;
  /// The gains to assume when none are given and the data cannot tell (no tau column), e.g.
  /// the preset's; empty = such a request is refused.
  std::optional<PdController> assumed_controller;

  /// Stopping rules (NLopt and LM alike): relative tolerances on x and f, evaluation and time budgets.
  double relative_x_tolerance = 1e-10;
  double relative_f_tolerance = 1e-14;
  int max_evaluations = 20000;
  double max_seconds = 120.0;
  /// Input-error: after the optimiser stops, polish with exact Gauss–Newton steps on the Gram
  /// form (microseconds each). Derivative-free optimisers often stall early in the narrow
  /// valleys of this problem; the polish takes them to the minimum. Evaluations it makes are
  /// counted and recorded like the optimiser's.
  bool refine = true;
  /// Two-stage: at most this many Gauss–Newton (Levenberg–Marquardt) output-error steps after
  /// the input-error start; it stops earlier once a step would move the estimate by less than
  /// a tenth of its standard error.
  int output_error_iterations = 20;
  /// Relative tolerance of the closed-loop simulations that output-error runs (absolute
  /// tolerance: the same number in rad). Finite differences use 1e-4 relative steps, far
  /// above the integrator's noise at this setting.
  double simulation_relative_tolerance = 1e-8;

  /// Cost history kept in the result: beyond this many records it is decimated, always
  /// keeping the first, the best and the last. The callback sees every evaluation.
  int history_limit = 5000;
  std::function<void(long index, double cost, const Eigen::VectorXd& theta)> on_evaluation;
  /// Checked at every evaluation; when it becomes true the run stops cleanly (stop reason
  /// "cancelled") with the best point so far.
  const std::atomic<bool>* cancel = nullptr;
};

/// One evaluation of the cost history (estimation/history.h); theta holds all 2n parameters.
using estimation::HistoryRecord;

/// A combination of parameters the data determines although its factors are not.
struct IdentifiableCombination {
  std::string name;      ///< e.g. "m1*l1^2"
  double value = 0.0;
  double std_error = 0.0;
};

struct IdentifiabilityReport {
  /// Singular values of the scaled Gauss–Newton Jacobian, largest first.
  Eigen::VectorXd singular_values;
  /// Parameters the data cannot determine on their own (empty when all are identifiable).
  std::vector<std::string> unidentifiable;
  /// What the data does determine in their place.
  std::vector<IdentifiableCombination> combinations;
  /// Plain-language findings, one per problem found.
  std::vector<std::string> findings;
  bool all_identifiable() const { return unidentifiable.empty(); }
  /// False for a parameter the data determine only in combination with others.
  bool determines_alone(const std::string& name) const {
    return std::find(unidentifiable.begin(), unidentifiable.end(), name) == unidentifiable.end();
  }
};

/// Where the controller gains the method used came from.
enum class GainSource {
  none,       ///< no gains used (input-error on the measured torque)
  given,      ///< IdentificationOptions::controller
  estimated,  ///< fitted to the data's τ, q and r (IdentificationResult::estimated_gains)
  assumed,    ///< IdentificationOptions::assumed_controller: neither given nor estimable
};
const char* to_string(GainSource source);

struct IdentificationResult {
  IdentificationMethod method = IdentificationMethod::input_error;
  std::string algorithm;               ///< the one that ran (the method's default when none was named)
  std::vector<std::string> names;      ///< m1..mn, l1..ln
  std::vector<bool> free;              ///< per parameter
  Eigen::VectorXd initial, estimate;   ///< θ
  /// Standard errors (NaN for fixed and unidentifiable parameters) and the correlation
  /// matrix of the free parameters (in `free` order).
  Eigen::VectorXd std_errors;
  Eigen::MatrixXd correlation;
  IdentifiabilityReport identifiability;

  double initial_cost = 0.0, final_cost = 0.0;
  long evaluations = 0;
  long simulations = 0;                ///< closed-loop simulations run (output-error)
  int refinement_steps = 0;            ///< accepted Gauss–Newton polish steps (input-error)
  double wall_seconds = 0.0;
  std::string stop_reason;             ///< e.g. "converged: relative step below 1e-10", "xtol_reached", "maxeval_reached", "cancelled"
  bool cancelled = false;

  FilterSettings filter;               ///< the filter used (chosen or given)
  bool filter_chosen_automatically = false;
  TorqueSource torque_source = TorqueSource::measured;
  /// The PD gains the method used (empty for GainSource::none) and where they came from.
  std::optional<PdController> controller;
  GainSource gain_source = GainSource::none;
  /// The gains fitted to the data whenever they carry τ, q and r, with the law's fit.
  std::optional<GainFit> estimated_gains;
  /// Is the final residual noise? Its RMS (filtered torque, N·m, for input-error; q, rad, for
  /// output-error and two-stage) beside what the measurement noise found in the raw data would
  /// leave there. A residual far above that (10×) is the method's bias, and the standard errors,
  /// which assume noise, then understate the error (a warning says so). NaN if not assessed.
  double residual_rms = std::numeric_limits<double>::quiet_NaN();
  double noise_rms = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::string> warnings;   ///< caveats users must read (e.g. about std errors)
  std::vector<HistoryRecord> history;  ///< bounded, see IdentificationOptions::history_limit
};

/// Estimates the parameters of `model` from `data`. Throws InputError for unusable input
/// (unknown names, starting values outside kMassRange/kLengthRange, bounds that exclude the
/// start, too few samples for the filter, missing ref/gains for the chosen method, ...) and
/// IdentificationError when the cost is not finite at the start or the end; everything else
/// is reported in the result.
IdentificationResult identify(const RobotModel& model, const Trajectory& data, const IdentificationOptions& options);

}  // namespace manipid

// excitation.h — optimal excitation trajectories for identification (Swevers, Ganseman, Tükel, De Schutter
// & Van Brussel, "Optimal robot excitation and identification", IEEE Trans. Robotics and Automation 13(5), 1997).
//
// Each joint follows a finite Fourier series of period T = 2π/ω_f with L harmonics:
//
//     q_k(t)  = q0_k + Σ_{l=1..L} [ a_kl/(ω_f l) sin(ω_f l t) − b_kl/(ω_f l) cos(ω_f l t) ]
//     q̇_k(t)  =        Σ_{l=1..L} [ a_kl cos(ω_f l t) + b_kl sin(ω_f l t) ]
//     q̈_k(t)  = ω_f ·  Σ_{l=1..L} l [ −a_kl sin(ω_f l t) + b_kl cos(ω_f l t) ]
//
// Periodic: a measurement can repeat the period and average the periods to cut noise. q0_k is the mean
// position over a period; the motion starts at q_k(0) = q0_k − Σ_l b_kl/(ω_f l).
//
// Starting and ending at rest. At t = 0 (and, by periodicity, at t = T, where q also returns to q_k(0)):
//
//     q̇_k(0) = Σ_l a_kl           q̈_k(0) = ω_f Σ_l l·b_kl
//
// so the trajectory starts and ends at rest exactly when, for every joint,
//
//     Σ_l a_kl = 0   and   Σ_l l·b_kl = 0.                                                        (R)
//
// The design meets (R) by construction, not by a penalty: each joint's a_k lies in the (L−1)-dimensional
// subspace orthogonal to (1, 1, …, 1) and b_k in the one orthogonal to (1, 2, …, L); the optimiser moves
// coordinates in orthonormal bases of those subspaces (so all its directions are alike — eliminating a_k1 =
// −Σ_{l≥2} a_kl instead would couple a_k1 to every other coefficient). L = 1 leaves nothing to move:
// harmonics must be at least 2. At the end the constraint is re-imposed on the first coefficients
// (a_k1 = −Σ_{l≥2} a_kl, b_k1 = −Σ_{l≥2} l b_kl), so the written sums are as close to 0 as rounding allows.
//
// Limits (resolved per joint by excitation_limits()): the URDF's position limits narrowed by
// `position_margin` on each side (continuous joints: none), the URDF's velocity limit (+∞ without <limit>)
// and `max_acceleration`. They hold for the continuous trajectory, for every t, not only on a grid (see
// design_excitation()), so a trajectory sampled at any step never leaves them.
//
// Criterion: the base regressor Y_b (the columns of robot/regressor.h's Y for the base parameters of
// robot/base_parameters.h, friction, offset and armature columns of the layout included), stacked at
// `samples` instants spread evenly over one period:
//   - condition: minimise cond(Y_b S), S scaling each column to unit norm (so kg and kg·m² columns
//     weigh alike; the unscaled number mostly measures units);
//   - logdet:    maximise log det(Y_bᵀ Y_b / N), the D-optimal design (its optimum does not depend on the
//     parameters' units: rescaling a column adds a constant to log det).
#pragma once

#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace manipid::robot {

/// The coefficients of one periodic excitation: everything needed to reproduce the motion (see the file
/// comment for the series). Units: rad and rad/s (m and m/s for prismatic joints).
struct FourierTrajectory {
  double period = 0.0;  ///< T, s
  Eigen::VectorXd q0;   ///< n: each joint's mean position over a period
  Eigen::MatrixXd a;    ///< n × L: cosine coefficients of q̇ (the sine terms of q), rad/s
  Eigen::MatrixXd b;    ///< n × L: sine coefficients of q̇ (the cosine terms of q), rad/s

  int joint_count() const { return static_cast<int>(q0.size()); }
  int harmonics() const { return static_cast<int>(a.cols()); }
  /// ω_f = 2π / T, rad/s.
  double angular_frequency() const;
  /// q(0) = q(T): where the motion starts and ends (at rest when (R) holds).
  Eigen::VectorXd start() const;
  /// Throws InputError unless the period is finite and positive, the sizes agree (q0: n, a and b: n × L,
  /// L ≥ 1) and every coefficient is finite.
  void validate() const;
};

enum class ExcitationCriterion {
  condition,  ///< minimise the condition number of the column-scaled base regressor
  logdet,     ///< maximise log det of the information matrix Y_bᵀ Y_b / N
};
const char* to_string(ExcitationCriterion criterion);
/// "condition" or "logdet"; InputError(field) otherwise.
ExcitationCriterion parse_excitation_criterion(const std::string& text, const std::string& field = "criterion");

/// What the optimiser reports after every evaluation (for a progress display; cheap to ignore).
struct ExcitationProgress {
  long evaluation = 0;      ///< 1, 2, …
  double value = 0.0;       ///< the criterion at this evaluation (condition number or log det)
  double best_value = 0.0;  ///< the best so far
  double seconds = 0.0;     ///< since design_excitation() started
};

struct ExcitationOptions {
  /// T, s. Longer periods reach lower frequencies (more room before the acceleration limit) but make the
  /// experiment longer; Swevers et al. used 10 s.
  double period = 10.0;
  /// L, 2..20. Each joint has 2L − 1 free coefficients (2L, less the two rest conditions, plus q0). Five
  /// (Swevers et al.) excite a 7-joint arm well; more harmonics mean more unknowns for the optimiser and
  /// motion closer to the acceleration limit's frequencies, rarely a better condition.
  int harmonics = 5;
  ExcitationCriterion criterion = ExcitationCriterion::condition;
  /// Which friction, offset and armature columns the regressor has: design for the model you will identify.
  ParameterLayout layout;
  /// Largest |q̈|, rad/s² (m/s² prismatic): one value for every joint, or one per joint. URDF has no
  /// acceleration limit, so it comes from here. 7.5 rad/s² is within what common arms reach on every joint
  /// (Panda: 7.5 to 20 rad/s² per joint), and enough for the default design to reach a 2.2 rad/s velocity
  /// limit even on its highest harmonic (ω_f · L · q̇_max = 0.63 · 5 · 2.2 ≈ 6.9 rad/s²), so the velocity
  /// and position limits, not this one, shape most joints' motion. Give the robot's own figures where known.
  Eigen::VectorXd max_acceleration = Eigen::VectorXd::Constant(1, 7.5);
  /// Distance kept from each position limit, rad (m prismatic): a tracking controller overshoots its
  /// reference a little, and a hard stop is not a place to identify friction. 0.05 rad ≈ 3°.
  double position_margin = 0.05;
  /// N: instants per period at which the regressor is stacked for the criterion; 0 = max(200, 40 L).
  /// The regressor's entries are products of the joint motion's harmonics, so N must resolve harmonic 2L
  /// and more: at least 8 L.
  int samples = 0;
  /// Random starting candidates evaluated before the local optimisation.
  int random_starts = 32;
  /// Local optimisations, from the best `local_starts` random candidates, each with an equal share of the
  /// evaluations left (a run that converges early leaves its share to the next). The criterion has many
  /// local minima: several shorter runs find a better one than a single long run.
  int local_starts = 4;
  /// Seeds the random starts: the same seed, options and robot give the same trajectory (unless
  /// max_seconds cuts the run short: time depends on the machine, evaluations do not).
  std::uint64_t seed = 1;
  /// Budget, s of wall time, checked at each evaluation. A backstop: the default evaluation budget ends a
  /// 7-joint design well before it, so results do not depend on the machine's speed.
  double max_seconds = 30.0;
  /// Budget of criterion evaluations, random starts included. 8000 take about 6 s for a 7-joint arm with 5
  /// harmonics (Release, one core; about 0.75 ms each); twice as many improve the condition number by a few
  /// per cent at most.
  int max_evaluations = 8000;
  /// Checked at each evaluation; when it becomes true the design stops and returns the best trajectory
  /// found so far (always within the limits), with termination `cancelled`.
  const std::atomic<bool>* cancel = nullptr;
  /// Called after each evaluation, in the calling thread.
  std::function<void(const ExcitationProgress&)> progress;

  /// Throws InputError naming the field ("period", "harmonics", "max_acceleration", "position_margin",
  /// "samples", "random_starts", "local_starts", "max_seconds", "max_evaluations", or "joint NAME" for a
  /// joint whose limits leave it no room to move) unless a design can run on `model`.
  void validate(const Model& model) const;
};

/// The limits a design keeps, per joint (n each): positions narrowed by the margin (±∞ for continuous
/// joints), the URDF's velocity limit (+∞ without <limit>), the acceleration limit.
struct ExcitationLimits {
  Eigen::VectorXd lower, upper;  ///< rad (m)
  Eigen::VectorXd velocity;      ///< rad/s (m/s)
  Eigen::VectorXd acceleration;  ///< rad/s² (m/s²)
};
/// Throws InputError as ExcitationOptions::validate does.
ExcitationLimits excitation_limits(const Model& model, const ExcitationOptions& options);

enum class LimitKind { lower, upper, velocity, acceleration };
const char* to_string(LimitKind kind);

/// A limit the trajectory reaches (within 1 %).
struct ActiveLimit {
  int joint = 0;           ///< k, 1..n
  std::string joint_name;  ///< the URDF joint's name
  LimitKind kind = LimitKind::velocity;
  double peak = 0.0;       ///< min q, max q, max |q̇| or max |q̈| over the period
  double limit = 0.0;      ///< the limit it is held to (margin included)
};

enum class ExcitationTermination {
  converged,        ///< every local run stopped improving before the budgets ran out
  max_evaluations,  ///< the evaluation budget ran out (the usual end: the criterion keeps creeping down)
  max_seconds,      ///< the time budget ran out
  cancelled,        ///< the cancel flag was set
  failure,          ///< NLopt failed (message says why); the best trajectory found is still returned
};
const char* to_string(ExcitationTermination termination);

/// How a design went (Ceres's Solver::Summary in spirit).
struct ExcitationSummary {
  ExcitationCriterion criterion = ExcitationCriterion::condition;
  /// The criterion (condition number or log det) of the local optimisation's start — the best random
  /// start — and of the result.
  double initial_value = 0.0;
  double final_value = 0.0;
  /// cond(Y_b S) of the start and of the result, whatever the criterion (computed by SVD).
  double initial_condition_number = 0.0;
  double condition_number = 0.0;
  /// log det(Y_bᵀ Y_b / N) of the result.
  double log_det = 0.0;
  int base_parameters = 0;  ///< columns of Y_b
  int samples = 0;          ///< N; Y_b has N·n rows
  int free_coefficients = 0;  ///< what the optimiser moved: n (2L − 1)
  long evaluations = 0;
  double wall_seconds = 0.0;
  ExcitationTermination termination = ExcitationTermination::failure;
  std::string message;  ///< why it stopped, in words
  /// The limits the result reaches, by joint. The optimiser fills each joint's room, so every joint has at
  /// least one.
  std::vector<ActiveLimit> active_limits;
  /// How much of each limit the result uses, n × 4 (lower, upper, velocity, acceleration): 1 = reaches
  /// it; positions as the share of the room between q0 and the limit; NaN where there is no limit.
  Eigen::MatrixXd usage;

  /// One line: "condition 8.75 -> 5.42, 57 base parameters, 8000 evaluations in 6.1 s, stopped:
  /// max_evaluations" (logdet: "logdet 127.4 -> 175.4 (condition number 9.28), ...").
  std::string brief_report() const;
};

struct ExcitationDesign {
  FourierTrajectory trajectory;
  ExcitationSummary summary;
};

/// Designs an excitation for `model` (see the file comment): random starts, then `local_starts`
/// derivative-free local optimisations (NLopt's LN_SBPLX) of the criterion over q0 and the coefficients
/// that keep (R), every candidate scaled joint by joint to its largest amplitude within the limits. Throws InputError for bad options (ExcitationOptions::validate). Never returns
/// a trajectory outside the limits: a cancelled or failed run returns the best one evaluated.
ExcitationDesign design_excitation(const Model& model, const ExcitationOptions& options = {});

/// Positions, rates and accelerations at evenly spaced instants.
struct SampledExcitation {
  Eigen::VectorXd t;                 ///< N + 1 instants 0, Δ, …, periods·T, s
  Eigen::MatrixXd q, qd, qdd;        ///< n × (N + 1), one column per instant (as stacked_regressor takes them)
};

/// Samples `trajectory` every `dt` seconds over `periods` periods, both ends included. dt must divide the
/// period (to a relative 1e-9) so the last sample falls on t = periods·T, at rest; the phases ω_f l t are
/// reduced exactly (integer arithmetic on the sample index), so every period is bitwise the same. Throws
/// InputError("dt") for dt outside [1e-6, 10] s, not dividing T, or giving fewer than 4L samples per
/// period (too coarse to show the highest harmonic) or more than 10^7 samples in all; InputError("periods")
/// for periods < 1.
SampledExcitation sample_excitation(const FourierTrajectory& trajectory, double dt, int periods = 1);
/// The number of whole periods in `duration` (s); InputError("duration") unless it is one (to 1e-9): a
/// trajectory ends at rest only after whole periods.
int whole_periods(double duration, double period);
/// The samples as a Trajectory (samples × joints): t, q, qd and qdd.
Trajectory to_trajectory(const SampledExcitation& sampled);

/// The checks of sample_excitation's dt and periods alone (for a period and harmonics), so a caller can
/// refuse a bad step before spending seconds on a design. Throws InputError("dt"/"periods"/"period").
void check_sampling(double period, int harmonics, double dt, int periods = 1);

/// The first sample of `sampled` outside `limits` (rounding at 1e-12 relative tolerated), if any.
struct LimitViolation {
  int joint = 0;  ///< k, 1..n
  LimitKind kind = LimitKind::velocity;
  double t = 0.0;
  double value = 0.0;
  double limit = 0.0;
};
std::optional<LimitViolation> first_limit_violation(const ExcitationLimits& limits, const SampledExcitation& sampled);

/// How well a trajectory excites the model, by the design's own measure.
struct ExcitationQuality {
  double condition_number = 0.0;  ///< cond(Y_b S), by SVD; +∞ when a base column is zero (rank lost)
  double log_det = 0.0;           ///< log det(Y_bᵀ Y_b / N); −∞ when singular
  int base_parameters = 0;
  int samples = 0;
};
/// The criteria of `trajectory` on `model` with options.layout and options.samples (the other options are
/// not used). For comparing designs, or a hand-made trajectory with a designed one.
ExcitationQuality excitation_quality(const Model& model, const FourierTrajectory& trajectory,
                                     const ExcitationOptions& options = {});

}  // namespace manipid::robot

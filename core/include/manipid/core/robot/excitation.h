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
// or `max_velocity` where lower, `max_acceleration`, `max_jerk` (none by default) and the torque: the
// URDF's effort limit (none where the URDF gives none or 0) or `max_torque`, for the torque the URDF's
// inertial parameters — or an identified model's, `torque_parameters` — predict. The kinematic limits hold
// for the continuous trajectory, for every t, not only on a grid (see design_excitation()), so a trajectory
// sampled at any step never leaves them. The torque, a nonlinear function of the motion, is held to
// kTorqueShare of its limit at 40 instants per period of the highest harmonic and checked at 4× as many,
// and every sample written is checked again (first_limit_violation).
//
// Start pose (`start_pose`, optional). A lab's arm stands somewhere when the run begins. The sampled
// output then opens with a ramp from that pose to the series' start q(0) and closes with the same ramp
// back: per joint the quintic rest-to-rest profile q = q_a + (q_b − q_a)(10s³ − 15s⁴ + 6s⁵), s = t/D, whose
// velocity and acceleration are 0 at both ends (so the junctions with the series, also at rest, are
// smooth in q, q̇ and q̈), and whose peaks are 1.875 Δ/D (q̇), 5.7735 Δ/D² (q̈) and 60 Δ/D³ (jerk, at the
// ends). D is the shortest time that keeps every joint's limits, the torque's included (plan_ramp()).
//
// Criterion: the base regressor Y_b (the columns of robot/regressor.h's Y for the base parameters of
// robot/base_parameters.h, friction, offset and armature columns of the layout included), stacked at
// `samples` instants spread evenly over one period:
//   - condition: minimise cond(Y_b S), S scaling each column to unit norm (so kg and kg·m² columns
//     weigh alike; the unscaled number mostly measures units);
//   - logdet:    maximise log det(Y_bᵀ Y_b / N), the D-optimal design (its optimum does not depend on the
//     parameters' units: rescaling a column adds a constant to log det).
//
// Payload (`target` payload). A payload on the tip link is identified from the torque an identified arm leaves
// (robot/payload.h): its regressor is the last body's ten columns times payload_to_last_body(), and the design's
// criterion is that 10-column matrix's instead of Y_b. Often the wrist alone can excite it: `moving_joints`
// names the joints that move; the others hold their mean pose (which the design still chooses: where the
// wrist stands relative to gravity matters), so a payload run can be a few seconds of wrist motion.
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

/// What a design excites (see the file comment).
enum class ExcitationTarget {
  arm,      ///< the arm's base parameters (the layout's friction, offset and armature columns included)
  payload,  ///< a payload's ten parameters on the tip link (robot/payload.h)
};
const char* to_string(ExcitationTarget target);
/// "arm" or "payload"; InputError(field) otherwise.
ExcitationTarget parse_excitation_target(const std::string& text, const std::string& field = "target");
/// "condition" or "logdet"; InputError(field) otherwise.
ExcitationCriterion parse_excitation_criterion(const std::string& text, const std::string& field = "criterion");

/// What the optimiser reports after every evaluation (for a progress display; cheap to ignore).
struct ExcitationProgress {
  long evaluation = 0;      ///< 1, 2, …
  double value = 0.0;       ///< the criterion at this evaluation (condition number or log det)
  double best_value = 0.0;  ///< at the best candidate so far (by the cost, whose centring tie-break may
                            ///< rank a candidate 0.025 % worse by the criterion first)
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
  /// The arm's base parameters, or a payload's ten on the tip link.
  ExcitationTarget target = ExcitationTarget::arm;
  /// Joints that move (0-based, each once); empty = all. The others hold their mean pose, which the design
  /// chooses within the middle half of their range as it does every joint's.
  std::vector<int> moving_joints;
  /// Which friction, offset and armature columns the regressor has: design for the model you will identify.
  ParameterLayout layout;
  /// Largest |q̈|, rad/s² (m/s² prismatic): one value for every joint, or one per joint. URDF has no
  /// acceleration limit, so it comes from here. 7.5 rad/s² is within what common arms reach on every joint
  /// (Panda: 7.5 to 20 rad/s² per joint), and enough for the default design to reach a 2.2 rad/s velocity
  /// limit even on its highest harmonic (ω_f · L · q̇_max = 0.63 · 5 · 2.2 ≈ 6.9 rad/s²), so the velocity
  /// and position limits, not this one, shape most joints' motion. Give the robot's own figures where known.
  Eigen::VectorXd max_acceleration = Eigen::VectorXd::Constant(1, 7.5);
  /// Largest |q̇|, rad/s (m/s): empty = the URDF's velocity limits; one value for every joint, or one per
  /// joint. Never above the URDF's own limit (the lower of the two holds): give it to run slower, e.g. at
  /// half speed on a first run.
  Eigen::VectorXd max_velocity;
  /// Largest |d³q/dt³| (jerk), rad/s³ (m/s³): empty = no jerk limit; one value, or one per joint. A
  /// series' jerk is ω_f l times its acceleration per harmonic (about 16 rad/s³ at the defaults' 7.5 rad/s²
  /// and 5 harmonics of a 10 s period: far below arms' jerk limits, e.g. the Panda's 5000–7500 rad/s³);
  /// the ramps' jerk is 60 Δ/D³. Give the arm's figures where its controller enforces them.
  Eigen::VectorXd max_jerk;
  /// Largest |τ|, N·m (N): empty = the URDF's effort limits (joints whose <limit> has no effort, or 0, have
  /// none); one value, or one per joint. Never above the URDF's own effort.
  Eigen::VectorXd max_torque;
  /// The model whose torque max_torque limits: standard parameters (robot/parameters.h) for
  /// `torque_layout` — an identified model's, whose friction counts too. Empty: the URDF's own inertial
  /// parameters, damping and friction (standard_parameters).
  ParameterLayout torque_layout;
  Eigen::VectorXd torque_parameters;
  /// Distance kept from each position limit, rad (m prismatic): a tracking controller overshoots its
  /// reference a little, a hard stop is not a place to identify friction, and some controllers stop the
  /// arm before its limit (Franka's reflexes trip within a few degrees of it). 0.1 rad ≈ 6°.
  double position_margin = 0.1;
  /// Where the arm stands before and after the run, rad (m), n values; empty = no ramp (the output starts
  /// at the series' own start q(0)). Must lie within the URDF's position limits (the margin need not hold
  /// there), and the torque limits must hold the arm still at it.
  Eigen::VectorXd start_pose;
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
  /// Budget, s of wall time, checked at each evaluation. A backstop only: the evaluation budget ends a
  /// 7-joint design in 6–16 s, far within it even on a loaded machine (at 30 s, a loaded machine stopped
  /// designs early, so their result depended on its speed).
  double max_seconds = 300.0;
  /// Budget of criterion evaluations, random starts included. 8000 take 6–16 s for a 7-joint arm with 5
  /// harmonics (Release, one core; 0.75–2 ms each, by the machine and by how often the torque limits bind:
  /// docs/performance.md); twice as many improve the condition number by a few per cent at most.
  int max_evaluations = 8000;
  /// Checked between evaluations and inside the long steps (the base parameters; the criterion of a
  /// many-joint design, in blocks of about 0.05 s): when it becomes true the design stops with termination
  /// `cancelled` — between evaluations with the best trajectory found so far (always within the limits),
  /// inside a step with none (an empty trajectory).
  const std::atomic<bool>* cancel = nullptr;
  /// Called after each evaluation, in the calling thread.
  std::function<void(const ExcitationProgress&)> progress;

  /// Throws InputError naming the field ("period", "harmonics", "moving_joints", "max_acceleration", "max_velocity",
  /// "max_jerk", "max_torque", "torque_parameters", "position_margin", "start_pose", "samples",
  /// "random_starts", "local_starts", "max_seconds", "max_evaluations", or "joint NAME" for a joint whose
  /// limits leave it no room to move) unless a design can run on `model`.
  void validate(const Model& model) const;
};

/// The share of a torque limit the design aims at on its grid (40 instants per period of the highest
/// harmonic): a sinusoid's peak lies at most 1 − cos(π/20) ≈ 1.2 % above its largest sample there, so
/// the continuous torque stays within the limit; the result is checked on a 4× finer grid.
inline constexpr double kTorqueShare = 0.98;

/// The limits a design keeps, per joint (n each): positions narrowed by the margin (±∞ for continuous
/// joints), velocity (the URDF's, or max_velocity where lower; +∞ without either), acceleration, jerk and
/// torque (+∞ where there is none), and the model whose torque is limited.
struct ExcitationLimits {
  Eigen::VectorXd lower, upper;  ///< rad (m)
  Eigen::VectorXd velocity;      ///< rad/s (m/s)
  Eigen::VectorXd acceleration;  ///< rad/s² (m/s²)
  Eigen::VectorXd jerk;          ///< rad/s³ (m/s³)
  Eigen::VectorXd torque;        ///< N·m (N)
  ParameterLayout torque_layout;       ///< the torque model: layout and standard parameters
  Eigen::VectorXd torque_parameters;
  bool any_torque() const;  ///< a finite torque limit on some joint
};
/// Throws InputError as ExcitationOptions::validate does.
ExcitationLimits excitation_limits(const Model& model, const ExcitationOptions& options);

enum class LimitKind { lower, upper, velocity, acceleration, jerk, torque };
inline constexpr int kLimitKinds = 6;
const char* to_string(LimitKind kind);

/// A limit the trajectory reaches (within 1 %).
struct ActiveLimit {
  int joint = 0;           ///< k, 1..n
  std::string joint_name;  ///< the URDF joint's name
  LimitKind kind = LimitKind::velocity;
  double peak = 0.0;       ///< min q, max q, max |q̇|, |q̈|, |jerk| or |τ| over the period
  double limit = 0.0;      ///< the limit it is held to (margin included)
};

/// The smooth move from a start pose to the series' start and back (see the file comment).
struct StartRamp {
  Eigen::VectorXd pose;    ///< n: where the arm stands, rad (m)
  Eigen::VectorXd target;  ///< n: the series' start q(0)
  double duration = 0.0;   ///< D, s: the shortest within every limit (the sampled ramp is rounded up to whole steps)
  /// Per joint, the ramp's peaks (n × 4: |q̇|, |q̈|, |jerk|, |τ|) at `duration`.
  Eigen::MatrixXd peaks;
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
  ExcitationTarget target = ExcitationTarget::arm;
  /// The criterion (condition number or log det) of the local optimisation's start — the best random
  /// start — and of the result.
  double initial_value = 0.0;
  double final_value = 0.0;
  /// cond(Y_b S) of the start and of the result, whatever the criterion (computed by SVD).
  double initial_condition_number = 0.0;
  double condition_number = 0.0;
  /// log det(Y_bᵀ Y_b / N) of the result.
  double log_det = 0.0;
  int base_parameters = 0;  ///< columns of the criterion's matrix: the base parameters (arm), or 10 (payload)
  int samples = 0;          ///< N; Y_b has N·n rows
  int free_coefficients = 0;  ///< what the optimiser moved: n + 2m(L − 1) for m moving joints (n (2L − 1) when all move)
  long evaluations = 0;
  double wall_seconds = 0.0;
  ExcitationTermination termination = ExcitationTermination::failure;
  std::string message;  ///< why it stopped, in words
  /// The limits the result reaches, by joint. The optimiser fills each moving joint's room, so every moving
  /// joint has at least one.
  std::vector<ActiveLimit> active_limits;
  /// How much of each limit the result uses, n × 6 (lower, upper, velocity, acceleration, jerk, torque —
  /// LimitKind's order): 1 = reaches it; positions as the share of the room between q0 and the limit; NaN
  /// where there is no limit.
  Eigen::MatrixXd usage;
  /// What the result reaches, n × 6 in the same order: min q, max q, max |q̇|, |q̈|, |jerk|, |τ| over a
  /// period (|τ| of the torque model, also where no torque limit holds).
  Eigen::MatrixXd peaks;
  /// The amplitude factor (0, 1] the torque limits left: 1 = the kinematic limits alone shape the motion.
  double torque_scale = 1.0;

  /// One line: "condition 8.75 -> 5.42, 57 base parameters, 8000 evaluations in 6.1 s, stopped:
  /// max_evaluations" (logdet: "logdet 127.4 -> 175.4 (condition number 9.28), ..."; a payload's: "10 payload
  /// parameters").
  std::string brief_report() const;
};

struct ExcitationDesign {
  FourierTrajectory trajectory;
  ExcitationSummary summary;
  std::optional<StartRamp> ramp;  ///< when options.start_pose was given
};

/// Designs an excitation for `model` (see the file comment): random starts, then `local_starts`
/// derivative-free local optimisations (NLopt's LN_SBPLX) of the criterion over q0 and the coefficients
/// that keep (R), every candidate scaled joint by joint to its largest amplitude within the limits. Throws InputError for bad options (ExcitationOptions::validate). Never returns
/// a trajectory outside the limits: a failed run returns the best one evaluated, a cancelled one the best
/// one or none (ExcitationOptions::cancel).
ExcitationDesign design_excitation(const Model& model, const ExcitationOptions& options = {});

/// The ramp from `pose` to `target` (n each) for `model`'s limits: the shortest D (s) whose quintic keeps
/// every joint's velocity, acceleration, jerk and torque limit. Throws InputError("start_pose") when the pose
/// leaves the URDF's position limits, or when the torque limits cannot hold the arm at rest at the pose or
/// the target (naming the joint, the torque and the limit), or along the ramp however slow.
StartRamp plan_ramp(const Model& model, const ExcitationLimits& limits, const Eigen::VectorXd& pose,
                    const Eigen::VectorXd& target);

/// Positions, rates and accelerations at evenly spaced instants.
struct SampledExcitation {
  Eigen::VectorXd t;                 ///< N + 1 instants 0, Δ, …, s
  Eigen::MatrixXd q, qd, qdd;        ///< n × (N + 1), one column per instant (as stacked_regressor takes them)
  Eigen::MatrixXd jerk;              ///< n × (N + 1): d³q/dt³ (one-sided at the junctions of ramp and series)
  double ramp_duration = 0.0;        ///< s: the ramp in (and out), whole steps; 0 without a start pose
};

/// Samples `trajectory` every `dt` seconds over `periods` periods, both ends included. dt must divide the
/// period (to a relative 1e-9) so the last sample falls on t = periods·T, at rest; the phases ω_f l t are
/// reduced exactly (integer arithmetic on the sample index), so every period is bitwise the same. Throws
/// InputError("dt") for dt outside [1e-6, 10] s, not dividing T, or giving fewer than 4L samples per
/// period (too coarse to show the highest harmonic) or more than 10^7 samples in all; InputError("periods")
/// for periods < 1.
SampledExcitation sample_excitation(const FourierTrajectory& trajectory, double dt, int periods = 1);
/// The design sampled: its series as above, between its ramp in and out when it has one (each ramp's
/// duration rounded up to whole steps of dt, so the series starts on a sample).
SampledExcitation sample_excitation(const ExcitationDesign& design, double dt, int periods = 1);
/// The number of whole periods in `duration` (s); InputError("duration") unless it is one (to 1e-9): a
/// trajectory ends at rest only after whole periods.
int whole_periods(double duration, double period);
/// The samples as a Trajectory (samples × joints): t, q, qd and qdd.
Trajectory to_trajectory(const SampledExcitation& sampled);

/// The checks of sample_excitation's dt and periods alone (for a period and harmonics), so a caller can
/// refuse a bad step before spending seconds on a design. Throws InputError("dt"/"periods"/"period").
void check_sampling(double period, int harmonics, double dt, int periods = 1);

/// The first sample of `sampled` outside `limits` (rounding at 1e-12 relative tolerated), if any: position,
/// velocity, acceleration and jerk; with `model`, also the torque (limits.torque for the limits' torque
/// model, by inverse dynamics at every sample).
struct LimitViolation {
  int joint = 0;  ///< k, 1..n
  LimitKind kind = LimitKind::velocity;
  double t = 0.0;
  double value = 0.0;
  double limit = 0.0;
};
std::optional<LimitViolation> first_limit_violation(const ExcitationLimits& limits, const SampledExcitation& sampled,
                                                    const Model* model = nullptr);
/// "the velocity limit of joint 3 (2.2 rad/s) at t = 1.25 s: 2.31": for a message.
std::string describe(const LimitViolation& violation);

/// How well a trajectory excites the model, by the design's own measure.
struct ExcitationQuality {
  double condition_number = 0.0;  ///< cond(Y_b S), by SVD; +∞ when a base column is zero (rank lost)
  double log_det = 0.0;           ///< log det(Y_bᵀ Y_b / N); −∞ when singular
  int base_parameters = 0;        ///< columns of Y_b (10 for a payload)
  int samples = 0;
};
/// The criteria of `trajectory` on `model` with options.layout, options.target and options.samples (the other
/// options are not used). For comparing designs, or a hand-made trajectory with a designed one.
ExcitationQuality excitation_quality(const Model& model, const FourierTrajectory& trajectory,
                                     const ExcitationOptions& options = {});

}  // namespace manipid::robot

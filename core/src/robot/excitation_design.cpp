// excitation_design.cpp — the excitation's design: the search space (q0 and the coefficients that keep the
// rest conditions, every joint scaled into its limits), random starts, then local runs of LN_SBPLX through
// core's one NLopt adapter (estimation/optimizer.h), and the summary (robot/excitation.h).
//
// How the limits are kept — by scaling, not by constraints handed to the optimiser. Every limit is a box
// on one joint's own motion (position, velocity, acceleration), and joint k's motion is q0_k + p_k(t) with
// p_k linear in its coefficients (a_k, b_k). So for any q0_k inside the position range and any direction of
// (a_k, b_k), there is a largest factor s_k that keeps p_k's scaled copy inside every limit of joint k —
// one division per limit (excitation_limits.cpp, which also bounds what lies between the grid's points).
// The optimiser moves q0 and the directions freely (bounds only); each evaluation scales every joint to its
// own largest feasible amplitude and evaluates the criterion there. Why:
//   - every trajectory evaluated is feasible, so a cancelled, timed-out or failed run still returns a
//     usable one, and nothing has to be projected or repaired at the end;
//   - the constraints are maxima over time: nonsmooth, and there would be 4n of them (COBYLA handles
//     that, slowly, in 60+ dimensions, and ends only approximately feasible; SLSQP would need their
//     gradients by finite differences of maxima, which NLopt's own documentation advises against);
//   - each joint uses all the room it has: more motion is more signal against the same measurement
//     noise, which the scale-free condition number does not see on its own. (For logdet, the D-optimal
//     criterion, more amplitude is always better, so the optimum lies on the limits anyway.)
// The price: a joint's amplitude is not a free choice — it always touches one of its limits.
//
// The torque couples the joints, so it is kept after that, by one factor γ ≤ 1 on every joint's motion
// about q0 (excitation_limits.cpp's TorqueGuard). A mean pose where the arm cannot even stand still within
// the torque limits is no candidate: its cost is kInfeasibleCost.
//
// The mean pose q0 stays in the middle half of each joint's range. Otherwise the optimiser parks joints by
// a limit for the whole run — Franka's reflexes trip there — because a mean by the limit is the one way it
// has to shrink a joint's amplitude, which the scaling otherwise always makes the largest (measured on the
// Panda: joint 1's mean at 93 % of its range, its motion cut to a tenth of the room on one side; with the
// middle half, condition 5.84 against 5.83). A tie-break then centres joints where the criterion does not
// care (the first joint of an upright arm changes no torque): the cost gets kCentring · mean((2u_k − 1)²),
// u_k q0's share of its range, at most 0.025 % of the criterion (the cost is its log).
//
// The optimiser: random starts (the best of `random_starts` candidates, seeded), then NLopt's LN_SBPLX on
// n + 2m(L − 1) coordinates (m joints moving: n (2L − 1) when all do), restarted from its best point while budget remains. See design_excitation().
#include "robot/excitation_internal.h"

#include "estimation/optimizer.h"
#include "manipid/core/errors.h"
#include "numbers.h"

#include <Eigen/QR>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace manipid::robot {
namespace {

using manipid::detail::kInfinity;
using detail::format_number;

using Clock = std::chrono::steady_clock;

/// A limit within 1 % of being reached is reported as active.
constexpr double kActiveUsage = 0.99;
/// The cost of a candidate whose mean pose the torque limits cannot hold: above any real one (a log).
constexpr double kInfeasibleCost = 1e3;
/// Where the mean pose may lie, as a share of each joint's range, and the weight of the tie-break toward
/// its middle (see the file comment).
constexpr double kMeanLow = 0.25;
constexpr double kMeanHigh = 0.75;
constexpr double kCentring = 1e-3;

/// An orthonormal basis (L × (L − 1)) of the vectors orthogonal to c: the last L − 1 columns of the
/// Householder reflection that maps c onto its first axis.
Eigen::MatrixXd orthogonal_complement(const Eigen::VectorXd& c) {
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(c);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(c.size(), c.size());
  return Q.rightCols(c.size() - 1);
}

/// The design's search space and objective. The optimiser's vector x holds, for the n joints and the m of them
/// that move (ExcitationOptions::moving_joints; j-th moving joint k_j):
///   x[k]                              u_k ∈ [¼, ¾]: q0_k = lower_k + u_k (upper_k − lower_k)
///   x[n + j(L−1) .. ]                 α_j (L − 1): a_{k_j} = N_a α_j, N_a ⟂ (1, …, 1)
///   x[n + m(L−1) + j(L−1) .. ]        β_j (L − 1): b_{k_j} = N_b β_j, N_b ⟂ (1, 2, …, L)
/// then every moving joint scaled to its largest feasible amplitude; a joint that does not move has a = b = 0.
/// (Each joint's (α, β) is a direction: its length does not matter.)
class DesignProblem {
 public:
  DesignProblem(const Model& model, const ExcitationOptions& options, const ExcitationLimits& limits,
                const detail::CriterionColumns& columns)
      : options_(options),
        limits_(limits),
        n_(model.joint_count()),
        L_(options.harmonics),
        period_(options.period),
        grid_(options.period, options.harmonics),
        criterion_(model, options.layout, columns, options.period, options.harmonics, detail::resolved_samples(options),
                   options.cancel),
        torque_(model, limits, options.period, options.harmonics, detail::resolved_samples(options)),
        q0_(n_),
        K_(n_, 2 * L_),
        work_(n_, grid_.points()) {
    Eigen::VectorXd ones = Eigen::VectorXd::Ones(L_), ramp(L_);
    for (int l = 1; l <= L_; ++l) ramp[l - 1] = l;
    Na_ = orthogonal_complement(ones);
    Nb_ = orthogonal_complement(ramp);
    if (options.moving_joints.empty()) {
      for (int k = 0; k < n_; ++k) moving_.push_back(k);
    } else {
      moving_ = options.moving_joints;
    }
    m_ = static_cast<int>(moving_.size());
    // q0's range: the position limits with margin; a 2π window for rotations without limits, ±1 m for
    // slides without (the criterion is periodic in a rotation's angle; a slide's offset is a guess).
    q0_lower_.resize(n_);
    q0_upper_.resize(n_);
    for (int k = 0; k < n_; ++k) {
      const double fallback = model.joints[static_cast<std::size_t>(k)].is_prismatic() ? 1.0 : std::numbers::pi;
      q0_lower_[k] = std::isfinite(limits.lower[k]) ? limits.lower[k] : -fallback;
      q0_upper_[k] = std::isfinite(limits.upper[k]) ? limits.upper[k] : fallback;
    }
  }

  int dimension() const { return n_ + 2 * m_ * (L_ - 1); }

  /// q0 and K for x, every joint scaled into its limits.
  void map(const double* x) {
    for (int k = 0; k < n_; ++k) q0_[k] = q0_lower_[k] + x[k] * (q0_upper_[k] - q0_lower_[k]);
    K_.setZero();
    for (int j = 0; j < m_; ++j) {
      const int k = moving_[static_cast<std::size_t>(j)];
      const Eigen::Map<const Eigen::VectorXd> alpha(x + n_ + j * (L_ - 1), L_ - 1);
      const Eigen::Map<const Eigen::VectorXd> beta(x + n_ + (m_ + j) * (L_ - 1), L_ - 1);
      K_.row(k).head(L_).noalias() = (Na_ * alpha).transpose();
      K_.row(k).tail(L_).noalias() = (Nb_ * beta).transpose();
    }
    grid_.peaks(K_, work_, peaks_);
    for (int k : moving_) K_.row(k) *= detail::largest_scale(peaks_[static_cast<std::size_t>(k)], q0_[k], limits_, k);
    torque_scale_ = 1.0;
    if (limits_.any_torque()) {
      torque_scale_ = torque_.largest_factor(q0_, K_);
      if (torque_scale_ >= 0.0) K_ *= torque_scale_;
    }
  }

  /// The criterion as a cost to minimise (log cond, or −log det, plus the centring tie-break) at x; value:
  /// the criterion itself (NaN when the torque limits cannot hold the mean pose).
  double cost(const double* x, double& value) {
    map(x);
    if (!feasible()) {
      value = std::numeric_limits<double>::quiet_NaN();
      return kInfeasibleCost;
    }
    criterion_.stack(q0_, K_);
    double log_condition = 0.0, log_det = 0.0;
    criterion_.fast_criteria(log_condition, log_det);
    double centring = 0.0;
    for (int k = 0; k < n_; ++k) centring += (2.0 * x[k] - 1.0) * (2.0 * x[k] - 1.0);
    centring *= kCentring / n_;
    if (options_.criterion == ExcitationCriterion::condition) {
      value = std::exp(log_condition);
      return log_condition + centring;
    }
    value = log_det;
    return -log_det + centring;
  }

  /// Whether the last map()'s mean pose keeps the torque limits at rest.
  bool feasible() const { return torque_scale_ >= 0.0; }
  /// The last map()'s factor from the torque limits (1: none binds).
  double torque_scale() const { return torque_scale_; }

  /// The trajectory for x, with (R) re-imposed on the first coefficients.
  FourierTrajectory trajectory(const double* x) {
    map(x);
    FourierTrajectory result;
    result.period = period_;
    result.q0 = q0_;
    result.a = K_.leftCols(L_);
    result.b = K_.rightCols(L_);
    for (int k = 0; k < n_; ++k) {
      double a_rest = 0.0, b_rest = 0.0;
      for (int l = 2; l <= L_; ++l) {
        a_rest += result.a(k, l - 1);
        b_rest += l * result.b(k, l - 1);
      }
      result.a(k, 0) = -a_rest;
      result.b(k, 0) = -b_rest;
    }
    return result;
  }

  /// A random point: q0 in the middle half of each range, directions standard normal.
  void random_point(std::mt19937_64& engine, Eigen::VectorXd& x) const {
    std::uniform_real_distribution<double> middle(kMeanLow, kMeanHigh);
    std::normal_distribution<double> normal(0.0, 1.0);
    x.resize(dimension());
    for (int k = 0; k < n_; ++k) x[k] = middle(engine);
    for (int i = n_; i < dimension(); ++i) x[i] = normal(engine);
    normalise_directions(x);
  }

  /// Each joint's (α_k, β_k) to unit length (the length is free: the scaling undoes it), so the optimiser's
  /// steps mean the same turn of direction for every joint.
  void normalise_directions(Eigen::VectorXd& x) const {
    for (int j = 0; j < m_; ++j) {
      double squares = 0.0;
      for_each_direction(j, [&](Eigen::Index i) { squares += x[i] * x[i]; });
      if (!(squares > 0.0)) continue;
      const double inverse = 1.0 / std::sqrt(squares);
      for_each_direction(j, [&](Eigen::Index i) { x[i] *= inverse; });
    }
  }

  void bounds(Eigen::VectorXd& lower, Eigen::VectorXd& upper) const {
    lower = Eigen::VectorXd::Constant(dimension(), -kDirectionBound);
    upper = Eigen::VectorXd::Constant(dimension(), kDirectionBound);
    lower.head(n_).setConstant(kMeanLow);
    upper.head(n_).setConstant(kMeanHigh);
  }

  Eigen::VectorXd initial_step() const {
    Eigen::VectorXd step = Eigen::VectorXd::Constant(dimension(), kDirectionStep);
    step.head(n_).setConstant(kPositionStep);
    return step;
  }

  detail::CriterionWorkspace& criterion() { return criterion_; }

 private:
  /// Directions start at unit length per joint; ±4 leaves them room to grow without letting a model-based
  /// optimiser wander along the length (which changes nothing).
  static constexpr double kDirectionBound = 4.0;
  /// First steps: a tenth of q0's range; a quarter of a unit direction's length per coordinate.
  static constexpr double kPositionStep = 0.1;
  static constexpr double kDirectionStep = 0.25;

  /// The coordinates of the j-th moving joint's direction (α_j, β_j).
  template <typename F>
  void for_each_direction(int j, F&& f) const {
    for (int l = 0; l < L_ - 1; ++l) {
      f(static_cast<Eigen::Index>(n_ + j * (L_ - 1) + l));
      f(static_cast<Eigen::Index>(n_ + (m_ + j) * (L_ - 1) + l));
    }
  }

  const ExcitationOptions& options_;
  const ExcitationLimits& limits_;
  int n_, L_;
  std::vector<int> moving_;  // the joints that move, in order
  int m_ = 0;
  double period_;
  Eigen::MatrixXd Na_, Nb_;
  Eigen::VectorXd q0_lower_, q0_upper_;
  detail::LimitGrid grid_;
  detail::CriterionWorkspace criterion_;
  detail::TorqueGuard torque_;
  double torque_scale_ = 1.0;
  Eigen::VectorXd q0_;
  Eigen::MatrixXd K_;
  Eigen::MatrixXd work_;
  std::vector<detail::Peaks> peaks_;
};

/// What stops a run before its next evaluation.
enum class Interrupt {
  none,
  cancelled,
  max_seconds,
  max_evaluations,
  run_budget,  ///< this local run's share of the evaluations is spent; the next run may start
};

/// Evaluation bookkeeping shared by the random starts and the local stage: counts, budget, best point.
struct Search {
  DesignProblem* problem = nullptr;
  const ExcitationOptions* options = nullptr;
  Clock::time_point started;
  long evaluations = 0;
  Eigen::VectorXd best_x;  // over the whole design
  double best_cost = kInfinity;
  double best_value = 0.0;
  long run_limit = std::numeric_limits<long>::max();  // evaluations at which the current local run stops
  Eigen::VectorXd run_best_x;  // over the current local run
  double run_best_cost = kInfinity;
  Interrupt interrupt = Interrupt::none;
  /// An exception from an evaluation inside a local run (the progress callback's, bad_alloc): the adapter
  /// would turn it into a stop reason, so it is kept here, the run stopped before its next evaluation,
  /// and rethrown once the adapter has returned.
  std::exception_ptr error;

  double seconds() const { return std::chrono::duration<double>(Clock::now() - started).count(); }

  /// Why the run must stop before the next evaluation, if it must.
  Interrupt check() const {
    if (options->cancel && options->cancel->load(std::memory_order_relaxed)) return Interrupt::cancelled;
    if (evaluations >= options->max_evaluations) return Interrupt::max_evaluations;
    if (seconds() >= options->max_seconds) return Interrupt::max_seconds;
    if (evaluations >= run_limit) return Interrupt::run_budget;
    return Interrupt::none;
  }

  void start_run(const Eigen::VectorXd& x, double cost, long limit) {
    run_best_x = x;
    run_best_cost = cost;
    run_limit = limit;
    interrupt = Interrupt::none;
  }

  double evaluate(const Eigen::VectorXd& x) {
    double value = 0.0;
    const double cost = problem->cost(x.data(), value);
    ++evaluations;
    if (cost < best_cost) {
      best_cost = cost;
      best_value = value;
      best_x = x;
    }
    if (cost < run_best_cost) {
      run_best_cost = cost;
      run_best_x = x;
    }
    if (options->progress) options->progress(ExcitationProgress{evaluations, value, best_value, seconds()});
    return cost;
  }
};

/// How a local run ended.
enum class RunEnd {
  finished,     ///< NLopt's own stop (a tolerance, roundoff) or its backstop budgets
  interrupted,  ///< stopped before an evaluation: search.interrupt says why
  failed,       ///< NLopt failed; `failure` says why
};

/// One LN_SBPLX run from x within the remaining budget, through core's NLopt adapter. An exception from an
/// evaluation (search.error) comes out of here once the adapter has returned.
RunEnd local_run(Search& search, Eigen::VectorXd x, std::string& failure) {
  DesignProblem& problem = *search.problem;
  const ExcitationOptions& options = *search.options;
  manipid::detail::MinimizeSettings settings;
  settings.algorithm = "LN_SBPLX";
  problem.bounds(settings.lower, settings.upper);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = std::clamp(x[i], settings.lower[i], settings.upper[i]);
  settings.free.assign(static_cast<std::size_t>(x.size()), true);
  // The coordinates are alike already (q0 as a share of its range, unit directions): no scaling.
  settings.scale_by_start = false;
  settings.initial_step = problem.initial_step();
  // The budget is enforced in `stop` (exactly, and with the reason known); NLopt's own limits are a
  // backstop one step beyond. Tolerances: the cost is a log, so 1e-7 absolute is a 1e-7 relative change of
  // the criterion, far below any difference that matters to identification; x within 1e-6 of its range.
  const long limit = std::min<long>(options.max_evaluations, search.run_limit);
  settings.max_evaluations = static_cast<int>(std::max(1L, limit - search.evaluations + 1));
  settings.max_seconds = std::max(1e-3, options.max_seconds - search.seconds() + 1.0);
  settings.relative_x_tolerance = 0.0;
  settings.relative_f_tolerance = 0.0;
  settings.absolute_f_tolerance = 1e-7;
  settings.absolute_x_tolerance = 1e-6;
  settings.stop = [&search] {
    if (search.error) return true;
    const Interrupt interrupt = search.check();
    if (interrupt == Interrupt::none) return false;
    search.interrupt = interrupt;
    return true;
  };
  const manipid::detail::CostFunction cost = [&search](const Eigen::VectorXd& point, Eigen::VectorXd*) {
    try {
      return search.evaluate(point);
    } catch (...) {
      search.error = std::current_exception();
      return kInfinity;
    }
  };
  const manipid::detail::MinimizeOutcome outcome = manipid::detail::minimize(cost, x, settings);
  if (search.error) std::rethrow_exception(search.error);
  if (outcome.failure) {
    failure = *outcome.failure;
    return RunEnd::failed;
  }
  return outcome.stopped ? RunEnd::interrupted : RunEnd::finished;
}

}  // namespace

const char* to_string(ExcitationTermination termination) {
  switch (termination) {
    case ExcitationTermination::converged: return "converged";
    case ExcitationTermination::max_evaluations: return "max_evaluations";
    case ExcitationTermination::max_seconds: return "max_seconds";
    case ExcitationTermination::cancelled: return "cancelled";
    case ExcitationTermination::failure: return "failure";
  }
  return "unknown";
}

std::string ExcitationSummary::brief_report() const {
  std::string text = std::string(to_string(criterion)) + " " + format_number(initial_value) + " -> " +
                     format_number(final_value);
  if (criterion == ExcitationCriterion::logdet) text += " (condition number " + format_number(condition_number) + ")";
  text += ", " + std::to_string(base_parameters) + (target == ExcitationTarget::payload ? " payload" : " base") +
          " parameters, " + std::to_string(evaluations) +
          " evaluations in " + format_number(wall_seconds) + " s, stopped: " + to_string(termination);
  return text;
}

namespace {

ExcitationDesign design(const Model& model, const ExcitationOptions& options) {
  const Clock::time_point started = Clock::now();
  const ExcitationLimits limits = excitation_limits(model, options);
  const detail::CriterionColumns columns = detail::criterion_columns(model, options);
  DesignProblem problem(model, options, limits, columns);
  Search search;
  search.problem = &problem;
  search.options = &options;
  search.started = started;

  // Random starts. The first evaluation always runs, so there is a best point to return whatever happens.
  std::mt19937_64 engine(options.seed);
  struct Candidate {
    double cost;
    Eigen::VectorXd x;
  };
  std::vector<Candidate> candidates;
  Eigen::VectorXd x;
  for (int start = 0; start < options.random_starts; ++start) {
    if (start > 0) {
      search.interrupt = search.check();
      if (search.interrupt != Interrupt::none) break;
    }
    problem.random_point(engine, x);
    candidates.push_back({search.evaluate(x), x});
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  const Eigen::VectorXd start_x = search.best_x;
  const double initial_value = search.best_value;

  // Local stage: `local_starts` runs from the best random starts, each with an equal share of the evaluations
  // left. The criterion has many local minima, so several shorter runs from different starts beat one long
  // run (Panda-like arm, condition, seeds 1–4, mean cond: 4 runs sharing 8000 evaluations 5.25, one run of
  // 8000 evaluations 5.45, one of 4000 5.58; UR5-like 4.60, 4.62, 4.63).
  //
  // Each run is LN_SBPLX (Rowan's Subplex: Nelder–Mead on a sequence of low-dimensional subspaces), made for
  // objectives with kinks — and this one has them: the scaling is a minimum over the limits of maxima over
  // time, the condition number a ratio of extreme eigenvalues, the Coulomb columns are sign(q̇). It is
  // restarted from the run's best point with fresh steps while that still improves. The alternatives, same
  // setting (Panda-like / UR5-like mean cond): LN_SBPLX 5.25 / 4.60, LN_PRAXIS 5.45 / 4.75, LN_BOBYQA
  // 5.56 / 4.80 (its quadratic models suffer at the kinks), LN_NELDERMEAD 5.65 / 4.64, LN_COBYLA 5.69 / 4.75
  // (and the slowest); LN_NEWUOA_BOUND matched SBPLX on one Panda-like run at 50 times the time (its own
  // linear algebra, O(d⁴) per step, dominates).
  bool failed = false;
  std::string failure;
  const int runs = std::min<int>(options.local_starts, static_cast<int>(candidates.size()));
  bool stopped = search.interrupt != Interrupt::none;
  for (int run = 0; run < runs && !stopped; ++run) {
    const long share = (options.max_evaluations - search.evaluations) / (runs - run);
    search.start_run(candidates[static_cast<std::size_t>(run)].x, candidates[static_cast<std::size_t>(run)].cost,
                     search.evaluations + share);
    while (true) {
      const double before = search.run_best_cost;
      x = search.run_best_x;
      problem.normalise_directions(x);
      const RunEnd end = local_run(search, x, failure);
      if (end == RunEnd::failed) failed = stopped = true;
      if (end != RunEnd::finished) break;
      search.interrupt = search.check();
      if (search.interrupt != Interrupt::none) break;
      if (!(search.run_best_cost < before - 1e-6)) break;  // a restart gained nothing: converged
    }
    if (search.interrupt != Interrupt::none && search.interrupt != Interrupt::run_budget) stopped = true;
  }
  if (search.interrupt == Interrupt::run_budget) search.interrupt = Interrupt::none;

  ExcitationDesign design;
  ExcitationSummary& summary = design.summary;
  summary.criterion = options.criterion;
  summary.target = options.target;
  summary.initial_value = initial_value;
  summary.final_value = search.best_value;
  summary.base_parameters = columns.size();
  summary.samples = problem.criterion().samples();
  summary.free_coefficients = problem.dimension();
  summary.evaluations = search.evaluations;
  switch (search.interrupt) {
    case Interrupt::cancelled:
      summary.termination = ExcitationTermination::cancelled;
      summary.message = "cancelled; the best trajectory found is returned";
      break;
    case Interrupt::max_seconds:
      summary.termination = ExcitationTermination::max_seconds;
      summary.message = "the time budget of " + format_number(options.max_seconds) + " s ran out";
      break;
    case Interrupt::max_evaluations:
      summary.termination = ExcitationTermination::max_evaluations;
      summary.message = "the budget of " + std::to_string(options.max_evaluations) + " evaluations ran out";
      break;
    case Interrupt::none:
    case Interrupt::run_budget:
      if (failed) {
        summary.termination = ExcitationTermination::failure;
        summary.message = "NLopt failed (" + failure + "); the best trajectory found is returned";
      } else {
        summary.termination = ExcitationTermination::converged;
        summary.message = "converged: in every local run, a restart no longer improved the criterion";
      }
      break;
  }

  // Every candidate's mean pose was beyond the torque limits at rest: nothing to return.
  if (!(search.best_cost < kInfeasibleCost)) {
    throw InputError("max_torque", "the torque limits cannot hold the arm at rest at any of the " +
                                       std::to_string(search.evaluations) +
                                       " mean poses tried: raise max_torque, or check the URDF's effort limits and "
                                       "masses (or the torque model's parameters)");
  }

  // The figures are reported by SVD (the optimiser saw the faster Gram form).
  design.trajectory = problem.trajectory(start_x.data());
  problem.criterion().stack(design.trajectory.q0, detail::stacked_coefficients(design.trajectory));
  summary.initial_condition_number = problem.criterion().exact_quality().condition_number;
  design.trajectory = problem.trajectory(search.best_x.data());
  summary.torque_scale = problem.torque_scale();

  // The torque was held at the criterion's instants with kTorqueShare to spare; on the report's 4× finer
  // grid a peak between them could still poke above a limit: then the motion shrinks until it does not.
  Eigen::MatrixXd peaks;
  summary.usage = detail::measured_usage(model, design.trajectory, limits, peaks);
  for (int shrink = 0; shrink < 50; ++shrink) {
    double worst = 0.0;
    for (int k = 0; k < model.joint_count(); ++k) {
      if (std::isfinite(summary.usage(k, 5))) worst = std::max(worst, summary.usage(k, 5));
    }
    if (!(worst > 1.0)) break;
    design.trajectory.a *= 0.995;
    design.trajectory.b *= 0.995;
    summary.torque_scale *= 0.995;
    summary.usage = detail::measured_usage(model, design.trajectory, limits, peaks);
  }
  summary.peaks = peaks;
  problem.criterion().stack(design.trajectory.q0, detail::stacked_coefficients(design.trajectory));
  const ExcitationQuality quality = problem.criterion().exact_quality();
  summary.condition_number = quality.condition_number;
  summary.log_det = quality.log_det;

  for (int k = 0; k < model.joint_count(); ++k) {
    const double bound[kLimitKinds] = {limits.lower[k],        limits.upper[k], limits.velocity[k],
                                       limits.acceleration[k], limits.jerk[k],  limits.torque[k]};
    for (int kind = 0; kind < kLimitKinds; ++kind) {
      if (!(summary.usage(k, kind) >= kActiveUsage)) continue;  // NaN (no limit) is never active
      summary.active_limits.push_back(ActiveLimit{k + 1, model.joints[static_cast<std::size_t>(k)].name,
                                                  static_cast<LimitKind>(kind), peaks(k, kind), bound[kind]});
    }
  }
  if (options.start_pose.size() != 0) design.ramp = plan_ramp(model, limits, options.start_pose, design.trajectory.start());
  summary.wall_seconds = std::chrono::duration<double>(Clock::now() - started).count();
  return design;
}

}  // namespace

ExcitationDesign design_excitation(const Model& model, const ExcitationOptions& options) {
  const Clock::time_point started = Clock::now();
  try {
    return design(model, options);
  } catch (const Interrupted& interrupted) {
    // Inside a long step (the base parameters, an evaluation or the final figures of a many-joint design):
    // the evaluation under way is not finished, so there is no figure to report beside a trajectory.
    ExcitationDesign cancelled;
    cancelled.summary.criterion = options.criterion;
    cancelled.summary.target = options.target;
    cancelled.summary.termination = ExcitationTermination::cancelled;
    cancelled.summary.message = std::string("cancelled: ") + interrupted.what() + "; no trajectory is returned";
    cancelled.summary.wall_seconds = std::chrono::duration<double>(Clock::now() - started).count();
    return cancelled;
  }
}

}  // namespace manipid::robot

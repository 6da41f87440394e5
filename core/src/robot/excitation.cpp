// excitation.cpp — optimal excitation trajectories: Fourier series at rest at both ends, scaled into the
// joint limits, optimised for the base regressor's condition number or log det (robot/excitation.h).
//
// How the limits are kept — by scaling, not by constraints handed to the optimiser. Every limit is a box
// on one joint's own motion (position, velocity, acceleration), and joint k's motion is q0_k + p_k(t) with
// p_k linear in its coefficients (a_k, b_k). So for any q0_k inside the position range and any direction of
// (a_k, b_k), there is a largest factor s_k that keeps p_k's scaled copy inside every limit of joint k —
// one division per limit. The optimiser moves q0 and the directions freely (bounds only); each evaluation
// scales every joint to its own largest feasible amplitude and evaluates the criterion there. Why:
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
// The limits hold for every t, not only on the grid where they are checked. On a grid of spacing h, a
// smooth periodic f with |f''| ≤ M has max_t f ≤ max_grid f + h² M / 8 (at the true maximum f' = 0, and
// the nearest grid point is at most h/2 away). For a harmonic of amplitude r at frequency ω l, |f''| ≤
// r (ω l)², so M ≤ Σ_l r_l (ω l)² is known from the coefficients. The grid has 64 points per period of the
// highest harmonic — 32 times its Nyquist rate — so the bound costs at most (2π/64)²/8 ≈ 0.12 % of the
// room, and a trajectory sampled at any step (the command's dt) stays inside.
//
// The optimiser: random starts (the best of `random_starts` candidates, seeded), then NLopt's LN_SBPLX on
// n (2L − 1) coordinates, restarted from its best point while budget remains. See design_excitation().
#include "manipid/core/robot/excitation.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/base_parameters.h"
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/regressor.h"
#include "manipid/core/signal/trajectory.h"
#include "numbers.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <nlopt.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <cstdio>
#include <exception>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

namespace manipid::robot {
namespace {

using manipid::detail::kInfinity;

using Clock = std::chrono::steady_clock;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

constexpr int kMinHarmonics = 2;   // the two rest conditions take one coefficient each of a and b
constexpr int kMaxHarmonics = 20;  // beyond any published excitation; the optimiser's dimension is n (2L − 1)
constexpr int kConstraintPointsPerHarmonic = 64;  // grid points per period of the highest harmonic
constexpr int kMaxSamples = 100000;
constexpr long kMaxSampledInstants = 10'000'000;
/// The optimiser's criterion goes through the Gram matrix, which squares the condition number: eigenvalue
/// ratios below ε ≈ 2.2e-16 are rounding, so a cond beyond ~1e8 only means "very bad" there (the reported
/// figure comes from an SVD). Eigenvalues are floored at λ_max / kConditionCap² so that the log stays
/// finite when rounding makes one zero or negative.
constexpr double kConditionCap = 1e16;
/// log det for a trajectory that leaves some base parameter unseen: below any real one (those are O(100)).
constexpr double kUnseenLogDet = -1e6;
/// A limit within 1 % of being reached is reported as active.
constexpr double kActiveUsage = 0.99;

std::string joint_field(const Model& model, int k) { return "joint " + model.joints[static_cast<std::size_t>(k)].name; }

std::string format_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

int resolved_samples(const ExcitationOptions& options) {
  return options.samples > 0 ? options.samples : std::max(200, 40 * options.harmonics);
}

/// An orthonormal basis (L × (L − 1)) of the vectors orthogonal to c: the last L − 1 columns of the
/// Householder reflection that maps c onto its first axis.
Eigen::MatrixXd orthogonal_complement(const Eigen::VectorXd& c) {
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(c);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(c.size(), c.size());
  return Q.rightCols(c.size() - 1);
}

/// Where in each of the N steps of a period the instants fall.
enum class Instants {
  starts,     ///< t_j = T j / N: the sampled trajectory, t = 0 included
  midpoints,  ///< t_j = T (j + ½) / N: the criterion's (see CriterionWorkspace)
};

/// The Fourier basis at N evenly spaced instants of one period, as 2L × N matrices, so that for K = [a b]
/// (n × 2L): p = K·position (q − q0), q̇ = K·velocity, q̈ = K·acceleration (n × N each). Phases are reduced
/// exactly in integers: ω l t_j = 2π ((l m_j) mod 2N) / 2N with m_j = 2j (starts) or 2j + 1 (midpoints).
struct HarmonicTable {
  Eigen::MatrixXd position, velocity, acceleration;

  HarmonicTable(double period, int harmonics, int instants, Instants where) {
    const int L = harmonics;
    const double omega = kTwoPi / period;
    const long steps = 2 * static_cast<long>(instants);
    position.resize(2 * L, instants);
    velocity.resize(2 * L, instants);
    acceleration.resize(2 * L, instants);
    for (int j = 0; j < instants; ++j) {
      const long m = 2 * static_cast<long>(j) + (where == Instants::midpoints ? 1 : 0);
      for (int l = 1; l <= L; ++l) {
        const long turns = (static_cast<long>(l) * m) % steps;
        const double phase = kTwoPi * static_cast<double>(turns) / static_cast<double>(steps);
        const double s = std::sin(phase), c = std::cos(phase), w = omega * l;
        position(l - 1, j) = s / w;
        position(L + l - 1, j) = -c / w;
        velocity(l - 1, j) = c;
        velocity(L + l - 1, j) = s;
        acceleration(l - 1, j) = -w * s;
        acceleration(L + l - 1, j) = w * c;
      }
    }
  }
};

/// K = [a b], n × 2L.
Eigen::MatrixXd stacked_coefficients(const FourierTrajectory& trajectory) {
  Eigen::MatrixXd K(trajectory.joint_count(), 2 * trajectory.harmonics());
  K << trajectory.a, trajectory.b;
  return K;
}

/// Peaks of one joint's motion over a period, from a grid plus the bound on what lies between its points
/// (see the file comment): an outer bound of the continuous trajectory's extremes.
struct Peaks {
  double highest = 0.0;  ///< max p (p = q − q0)
  double lowest = 0.0;   ///< min p
  double velocity = 0.0;
  double acceleration = 0.0;
};

/// The grid on which the limits are checked, with the inter-sample bounds.
class LimitGrid {
 public:
  LimitGrid(double period, int harmonics)
      : harmonics_(harmonics),
        omega_(kTwoPi / period),
        spacing_(period / (kConstraintPointsPerHarmonic * harmonics)),
        table_(period, harmonics, kConstraintPointsPerHarmonic * harmonics, Instants::starts) {}

  /// Outer bounds of each joint's extremes for coefficients K (n × 2L); `work` is scratch (n × grid).
  void peaks(const Eigen::MatrixXd& K, Eigen::MatrixXd& work, std::vector<Peaks>& out) const {
    const Eigen::Index n = K.rows();
    out.resize(static_cast<std::size_t>(n));
    const double h2 = spacing_ * spacing_ / 8.0;
    // Curvature bounds: Σ_l r_l (ω l)^m for m = 1 (position's f'' is q̈), 2 (q̇), 3 (q̈).
    for (Eigen::Index k = 0; k < n; ++k) {
      double m1 = 0.0, m2 = 0.0, m3 = 0.0;
      for (int l = 1; l <= harmonics_; ++l) {
        const double r = std::hypot(K(k, l - 1), K(k, harmonics_ + l - 1));
        const double w = omega_ * l;
        m1 += r * w;
        m2 += r * w * w;
        m3 += r * w * w * w;
      }
      Peaks& p = out[static_cast<std::size_t>(k)];
      p.highest = h2 * m1;
      p.lowest = -h2 * m1;
      p.velocity = h2 * m2;
      p.acceleration = h2 * m3;
    }
    work.noalias() = K * table_.position;
    for (Eigen::Index k = 0; k < n; ++k) {
      out[static_cast<std::size_t>(k)].highest += work.row(k).maxCoeff();
      out[static_cast<std::size_t>(k)].lowest += work.row(k).minCoeff();
    }
    work.noalias() = K * table_.velocity;
    for (Eigen::Index k = 0; k < n; ++k) out[static_cast<std::size_t>(k)].velocity += work.row(k).cwiseAbs().maxCoeff();
    work.noalias() = K * table_.acceleration;
    for (Eigen::Index k = 0; k < n; ++k) {
      out[static_cast<std::size_t>(k)].acceleration += work.row(k).cwiseAbs().maxCoeff();
    }
  }

  int points() const { return static_cast<int>(table_.position.cols()); }

 private:
  int harmonics_;
  double omega_;
  double spacing_;
  HarmonicTable table_;
};

/// The largest s ≥ 0 with q0 + s·p inside every limit of the joint, p's extremes bounded by `peaks`.
double largest_scale(const Peaks& peaks, double q0, double lower, double upper, double velocity, double acceleration) {
  double s = kInfinity;
  if (std::isfinite(velocity) && peaks.velocity > 0.0) s = std::min(s, velocity / peaks.velocity);
  if (peaks.acceleration > 0.0) s = std::min(s, acceleration / peaks.acceleration);
  if (std::isfinite(upper) && peaks.highest > 0.0) s = std::min(s, (upper - q0) / peaks.highest);
  if (std::isfinite(lower) && peaks.lowest < 0.0) s = std::min(s, (q0 - lower) / -peaks.lowest);
  // No motion at all (every coefficient 0) leaves s infinite: nothing to scale.
  return std::isfinite(s) ? std::max(s, 0.0) : 0.0;
}

/// The base regressor stacked over N instants of one period, and the criteria from it. One per design
/// (or per quality evaluation): the Data and every matrix are sized once, nothing is allocated per call.
///
/// The instants are the midpoints t_j = T (j + ½) / N — as good a quadrature of a periodic integrand as
/// the starts T j / N, and they avoid t = 0, where the design makes q̇ = 0 exactly: there the Coulomb
/// column sign(q̇) would be sign(±1e-17), decided by rounding (measured: cond moved by 2.5 % between a
/// trajectory and the same one with its rest conditions re-imposed to the last bit).
class CriterionWorkspace {
 public:
  CriterionWorkspace(const Model& model, const ParameterLayout& layout, const BaseParameters& base, double period,
                     int harmonics, int samples)
      : model_(model),
        layout_(layout),
        base_(base),
        n_(model.joint_count()),
        samples_(samples),
        table_(period, harmonics, samples, Instants::midpoints),
        data_(model),
        q_(n_, samples),
        qd_(n_, samples),
        qdd_(n_, samples),
        Y_(static_cast<Eigen::Index>(samples) * n_, layout.size(n_)),
        Yb_(static_cast<Eigen::Index>(samples) * n_, base.size()),
        gram_(base.size(), base.size()),
        scaled_gram_(base.size(), base.size()),
        norms_(base.size()),
        eigen_(base.size()) {}

  int samples() const { return samples_; }

  /// Fills Y_b for q0 (n) and K = [a b] (n × 2L).
  void stack(const Eigen::VectorXd& q0, const Eigen::MatrixXd& K) {
    q_.noalias() = K * table_.position;
    q_.colwise() += q0;
    qd_.noalias() = K * table_.velocity;
    qdd_.noalias() = K * table_.acceleration;
    stacked_regressor(model_, data_, layout_, q_, qd_, qdd_, Y_);
    for (int i = 0; i < base_.size(); ++i) Yb_.col(i) = Y_.col(base_.independent[static_cast<std::size_t>(i)]);
  }

  /// From the stacked Y_b, through the Gram matrix (fast; what the optimiser sees): log cond(Y_b S) and
  /// log det(Y_bᵀ Y_b / N). Squaring loses nothing that matters here: condition numbers up to ~1e7 come
  /// out to several digits, beyond that the trajectory is bad whatever the digits. Capped, never NaN.
  void fast_criteria(double& log_condition, double& log_det) {
    gram_.setZero();
    gram_.selfadjointView<Eigen::Lower>().rankUpdate(Yb_.transpose());
    const Eigen::Index b = gram_.rows();
    for (Eigen::Index i = 0; i < b; ++i) norms_[i] = std::sqrt(gram_(i, i));
    // A base column that is zero over the whole trajectory (a joint frozen at its limit: a parameter it
    // cannot see), or anything not finite: the worst value, never a NaN into the eigensolver.
    if (b == 0 || !gram_.allFinite() || !(norms_.minCoeff() > 0.0)) {
      log_condition = std::log(kConditionCap);
      log_det = kUnseenLogDet;
      return;
    }
    for (Eigen::Index j = 0; j < b; ++j) {
      for (Eigen::Index i = j; i < b; ++i) scaled_gram_(i, j) = gram_(i, j) / (norms_[i] * norms_[j]);
    }
    eigen_.compute(scaled_gram_, Eigen::EigenvaluesOnly);
    const Eigen::VectorXd& lambda = eigen_.eigenvalues();  // ascending
    const double top = lambda[b - 1];
    const double floor = top / (kConditionCap * kConditionCap);
    const double bottom = std::max(lambda[0], floor);
    log_condition = 0.5 * std::log(top / bottom);
    double sum = 0.0;
    for (Eigen::Index i = 0; i < b; ++i) sum += std::log(std::max(lambda[i], floor)) + 2.0 * std::log(norms_[i]);
    log_det = sum - static_cast<double>(b) * std::log(static_cast<double>(samples_));
  }

  /// By SVD of the column-scaled Y_b: the reported figures.
  ExcitationQuality exact_quality() const {
    ExcitationQuality quality;
    quality.base_parameters = base_.size();
    quality.samples = samples_;
    const Eigen::Index b = Yb_.cols();
    if (b == 0) {
      quality.condition_number = kInfinity;
      quality.log_det = -kInfinity;
      return quality;
    }
    Eigen::VectorXd norms = Yb_.colwise().norm().transpose();
    if (!Yb_.allFinite() || !(norms.minCoeff() > 0.0)) {
      quality.condition_number = kInfinity;
      quality.log_det = -kInfinity;
      return quality;
    }
    const Eigen::MatrixXd scaled = Yb_ * norms.cwiseInverse().asDiagonal();
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(scaled);
    const Eigen::VectorXd& sigma = svd.singularValues();  // descending
    const double smallest = sigma[b - 1];
    quality.condition_number = smallest > 0.0 ? sigma[0] / smallest : kInfinity;
    if (smallest > 0.0) {
      quality.log_det = 2.0 * (sigma.array().log().sum() + norms.array().log().sum()) -
                        static_cast<double>(b) * std::log(static_cast<double>(samples_));
    } else {
      quality.log_det = -kInfinity;
    }
    return quality;
  }

 private:
  const Model& model_;
  const ParameterLayout& layout_;
  const BaseParameters& base_;
  int n_;
  int samples_;
  HarmonicTable table_;
  Data data_;
  Eigen::MatrixXd q_, qd_, qdd_;
  Eigen::MatrixXd Y_, Yb_;
  Eigen::MatrixXd gram_, scaled_gram_;
  Eigen::VectorXd norms_;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen_;
};

/// The design's search space and objective. The optimiser's vector x holds, for the n joints:
///   x[k]                              u_k ∈ [0, 1]: q0_k = lower_k + u_k (upper_k − lower_k)
///   x[n + k(L−1) .. ]                 α_k (L − 1): a_k = N_a α_k, N_a ⟂ (1, …, 1)
///   x[n + n(L−1) + k(L−1) .. ]        β_k (L − 1): b_k = N_b β_k, N_b ⟂ (1, 2, …, L)
/// then every joint scaled to its largest feasible amplitude. (Each joint's (α_k, β_k) is a direction: its
/// length does not matter.)
class DesignProblem {
 public:
  DesignProblem(const Model& model, const ExcitationOptions& options, const ExcitationLimits& limits,
                const BaseParameters& base)
      : options_(options),
        limits_(limits),
        n_(model.joint_count()),
        L_(options.harmonics),
        period_(options.period),
        grid_(options.period, options.harmonics),
        criterion_(model, options.layout, base, options.period, options.harmonics, resolved_samples(options)),
        q0_(n_),
        K_(n_, 2 * L_),
        work_(n_, grid_.points()) {
    Eigen::VectorXd ones = Eigen::VectorXd::Ones(L_), ramp(L_);
    for (int l = 1; l <= L_; ++l) ramp[l - 1] = l;
    Na_ = orthogonal_complement(ones);
    Nb_ = orthogonal_complement(ramp);
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

  int dimension() const { return n_ * (2 * L_ - 1); }

  /// q0 and K for x, every joint scaled into its limits.
  void map(const double* x) {
    for (int k = 0; k < n_; ++k) {
      q0_[k] = q0_lower_[k] + x[k] * (q0_upper_[k] - q0_lower_[k]);
      const Eigen::Map<const Eigen::VectorXd> alpha(x + n_ + k * (L_ - 1), L_ - 1);
      const Eigen::Map<const Eigen::VectorXd> beta(x + n_ + (n_ + k) * (L_ - 1), L_ - 1);
      K_.row(k).head(L_).noalias() = (Na_ * alpha).transpose();
      K_.row(k).tail(L_).noalias() = (Nb_ * beta).transpose();
    }
    grid_.peaks(K_, work_, peaks_);
    for (int k = 0; k < n_; ++k) {
      const double s = largest_scale(peaks_[static_cast<std::size_t>(k)], q0_[k], limits_.lower[k], limits_.upper[k],
                                     limits_.velocity[k], limits_.acceleration[k]);
      K_.row(k) *= s;
    }
  }

  /// The criterion as a cost to minimise (log cond, or −log det) at x; value: the criterion itself.
  double cost(const double* x, double& value) {
    map(x);
    criterion_.stack(q0_, K_);
    double log_condition = 0.0, log_det = 0.0;
    criterion_.fast_criteria(log_condition, log_det);
    if (options_.criterion == ExcitationCriterion::condition) {
      value = std::exp(log_condition);
      return log_condition;
    }
    value = log_det;
    return -log_det;
  }

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
  void random_point(std::mt19937_64& engine, std::vector<double>& x) const {
    std::uniform_real_distribution<double> middle(0.25, 0.75);
    std::normal_distribution<double> normal(0.0, 1.0);
    x.resize(static_cast<std::size_t>(dimension()));
    for (int k = 0; k < n_; ++k) x[static_cast<std::size_t>(k)] = middle(engine);
    for (int i = n_; i < dimension(); ++i) x[static_cast<std::size_t>(i)] = normal(engine);
    normalise_directions(x);
  }

  /// Each joint's (α_k, β_k) to unit length (the length is free: the scaling undoes it), so the optimiser's
  /// steps mean the same turn of direction for every joint.
  void normalise_directions(std::vector<double>& x) const {
    for (int k = 0; k < n_; ++k) {
      double squares = 0.0;
      for_each_direction(k, [&](std::size_t i) { squares += x[i] * x[i]; });
      if (!(squares > 0.0)) continue;
      const double inverse = 1.0 / std::sqrt(squares);
      for_each_direction(k, [&](std::size_t i) { x[i] *= inverse; });
    }
  }

  void bounds(std::vector<double>& lower, std::vector<double>& upper) const {
    lower.assign(static_cast<std::size_t>(dimension()), -kDirectionBound);
    upper.assign(static_cast<std::size_t>(dimension()), kDirectionBound);
    for (int k = 0; k < n_; ++k) {
      lower[static_cast<std::size_t>(k)] = 0.0;
      upper[static_cast<std::size_t>(k)] = 1.0;
    }
  }

  std::vector<double> initial_step() const {
    std::vector<double> step(static_cast<std::size_t>(dimension()), kDirectionStep);
    for (int k = 0; k < n_; ++k) step[static_cast<std::size_t>(k)] = kPositionStep;
    return step;
  }

  CriterionWorkspace& criterion() { return criterion_; }

 private:
  /// Directions start at unit length per joint; ±4 leaves them room to grow without letting a model-based
  /// optimiser wander along the length (which changes nothing).
  static constexpr double kDirectionBound = 4.0;
  /// First steps: a tenth of q0's range; a quarter of a unit direction's length per coordinate.
  static constexpr double kPositionStep = 0.1;
  static constexpr double kDirectionStep = 0.25;

  template <typename F>
  void for_each_direction(int k, F&& f) const {
    for (int l = 0; l < L_ - 1; ++l) {
      f(static_cast<std::size_t>(n_ + k * (L_ - 1) + l));
      f(static_cast<std::size_t>(n_ + (n_ + k) * (L_ - 1) + l));
    }
  }

  const ExcitationOptions& options_;
  const ExcitationLimits& limits_;
  int n_, L_;
  double period_;
  Eigen::MatrixXd Na_, Nb_;
  Eigen::VectorXd q0_lower_, q0_upper_;
  LimitGrid grid_;
  CriterionWorkspace criterion_;
  Eigen::VectorXd q0_;
  Eigen::MatrixXd K_;
  Eigen::MatrixXd work_;
  std::vector<Peaks> peaks_;
};

/// What stops a run from inside the objective (NLopt turns a thrown forced_stop into a graceful stop).
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
  std::vector<double> best_x;  // over the whole design
  double best_cost = kInfinity;
  double best_value = 0.0;
  long run_limit = std::numeric_limits<long>::max();  // evaluations at which the current local run stops
  std::vector<double> run_best_x;  // over the current local run
  double run_best_cost = kInfinity;
  Interrupt interrupt = Interrupt::none;
  /// An exception from inside the objective (the progress callback's, bad_alloc): NLopt would replace it
  /// by a plain runtime_error, so it is kept here and rethrown once NLopt has returned.
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

  void start_run(const std::vector<double>& x, double cost, long limit) {
    run_best_x = x;
    run_best_cost = cost;
    run_limit = limit;
    interrupt = Interrupt::none;
  }

  double evaluate(const double* x, std::size_t size) {
    double value = 0.0;
    const double cost = problem->cost(x, value);
    ++evaluations;
    if (cost < best_cost) {
      best_cost = cost;
      best_value = value;
      best_x.assign(x, x + size);
    }
    if (cost < run_best_cost) {
      run_best_cost = cost;
      run_best_x.assign(x, x + size);
    }
    if (options->progress) options->progress(ExcitationProgress{evaluations, value, best_value, seconds()});
    return cost;
  }
};

double nlopt_objective(unsigned dimension, const double* x, double* gradient, void* data) {
  Search& search = *static_cast<Search*>(data);
  (void)gradient;  // derivative-free algorithms only
  const Interrupt interrupt = search.check();
  if (interrupt != Interrupt::none) {
    search.interrupt = interrupt;
    throw nlopt::forced_stop();
  }
  try {
    return search.evaluate(x, dimension);
  } catch (...) {
    search.error = std::current_exception();
    throw nlopt::forced_stop();
  }
}

/// One LN_SBPLX run from x (in place) within the remaining budget. Returns NLopt's result, or FORCED_STOP
/// when the objective stopped it (search.interrupt says why), or FAILURE with `failure` set.
nlopt::result local_search(Search& search, std::vector<double>& x, std::string& failure) {
  DesignProblem& problem = *search.problem;
  const ExcitationOptions& options = *search.options;
  const unsigned dimension = static_cast<unsigned>(problem.dimension());
  std::vector<double> lower, upper;
  problem.bounds(lower, upper);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::clamp(x[i], lower[i], upper[i]);

  // Built in place and never copied or moved once the objective is set (the C++ wrapper keeps `this`).
  nlopt::opt optimizer(nlopt::LN_SBPLX, dimension);
  optimizer.set_min_objective(nlopt_objective, &search);
  optimizer.set_lower_bounds(lower);
  optimizer.set_upper_bounds(upper);
  optimizer.set_initial_step(problem.initial_step());
  // The budget is enforced in the objective (exactly, and with the reason known); NLopt's own limits are a
  // backstop one step beyond. Tolerances: the cost is a log, so 1e-7 absolute is a 1e-7 relative change of
  // the criterion, far below any difference that matters to identification; x within 1e-6 of its range.
  const long limit = std::min<long>(options.max_evaluations, search.run_limit);
  optimizer.set_maxeval(static_cast<int>(std::max(1L, limit - search.evaluations + 1)));
  optimizer.set_maxtime(std::max(1e-3, options.max_seconds - search.seconds() + 1.0));
  optimizer.set_ftol_abs(1e-7);
  optimizer.set_xtol_abs(1e-6);
  double cost = 0.0;
  nlopt::result result = nlopt::FAILURE;
  try {
    result = optimizer.optimize(x, cost);
  } catch (const nlopt::forced_stop&) {
    result = nlopt::FORCED_STOP;
  } catch (const nlopt::roundoff_limited&) {
    result = nlopt::ROUNDOFF_LIMITED;  // NLopt: "typically still a useful result"
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& error) {
    failure = error.what();
    result = nlopt::FAILURE;
  }
  if (search.error) std::rethrow_exception(search.error);
  return result;
}

/// Peaks measured on a grid 4× finer than the limit grid (what the trajectory actually reaches, for the
/// report; the design's guarantee comes from the bound, not from this).
Eigen::MatrixXd measured_usage(const FourierTrajectory& trajectory, const ExcitationLimits& limits,
                               Eigen::MatrixXd& peaks) {
  const int n = trajectory.joint_count();
  const int points = 4 * kConstraintPointsPerHarmonic * trajectory.harmonics();
  const HarmonicTable table(trajectory.period, trajectory.harmonics(), points, Instants::starts);
  const Eigen::MatrixXd K = stacked_coefficients(trajectory);
  const Eigen::MatrixXd p = K * table.position, v = K * table.velocity, a = K * table.acceleration;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Eigen::MatrixXd usage = Eigen::MatrixXd::Constant(n, 4, nan);
  peaks.resize(n, 4);
  for (int k = 0; k < n; ++k) {
    const double q0 = trajectory.q0[k];
    peaks(k, 0) = q0 + p.row(k).minCoeff();
    peaks(k, 1) = q0 + p.row(k).maxCoeff();
    peaks(k, 2) = v.row(k).cwiseAbs().maxCoeff();
    peaks(k, 3) = a.row(k).cwiseAbs().maxCoeff();
    if (std::isfinite(limits.lower[k])) {
      usage(k, 0) = q0 > limits.lower[k] ? (q0 - peaks(k, 0)) / (q0 - limits.lower[k]) : 1.0;
    }
    if (std::isfinite(limits.upper[k])) {
      usage(k, 1) = q0 < limits.upper[k] ? (peaks(k, 1) - q0) / (limits.upper[k] - q0) : 1.0;
    }
    if (std::isfinite(limits.velocity[k])) usage(k, 2) = peaks(k, 2) / limits.velocity[k];
    usage(k, 3) = peaks(k, 3) / limits.acceleration[k];
  }
  return usage;
}

}  // namespace

// ---- FourierTrajectory ---------------------------------------------------------------------

double FourierTrajectory::angular_frequency() const { return kTwoPi / period; }

Eigen::VectorXd FourierTrajectory::start() const {
  Eigen::VectorXd q = q0;
  const double omega = angular_frequency();
  for (int l = 1; l <= harmonics(); ++l) q -= b.col(l - 1) / (omega * l);
  return q;
}

void FourierTrajectory::validate() const {
  if (!(std::isfinite(period) && period > 0.0)) {
    throw InputError("period", "the period must be a positive number of seconds, got " + format_number(period));
  }
  const Eigen::Index n = q0.size();
  if (n == 0) throw InputError("q0", "the trajectory has no joints");
  if (a.rows() != n || b.rows() != n || a.cols() != b.cols() || a.cols() < 1) {
    throw InputError("a", "the coefficients a (" + std::to_string(a.rows()) + " × " + std::to_string(a.cols()) +
                              ") and b (" + std::to_string(b.rows()) + " × " + std::to_string(b.cols()) +
                              ") must both be n × L with n = " + std::to_string(n) + " and L ≥ 1");
  }
  if (!q0.allFinite()) throw InputError("q0", "q0 has a value that is not finite");
  if (!a.allFinite()) throw InputError("a", "a has a coefficient that is not finite");
  if (!b.allFinite()) throw InputError("b", "b has a coefficient that is not finite");
}

// ---- Names -----------------------------------------------------------------------------------

const char* to_string(ExcitationCriterion criterion) {
  switch (criterion) {
    case ExcitationCriterion::condition: return "condition";
    case ExcitationCriterion::logdet: return "logdet";
  }
  return "unknown";
}

ExcitationCriterion parse_excitation_criterion(const std::string& text, const std::string& field) {
  if (text == "condition") return ExcitationCriterion::condition;
  if (text == "logdet") return ExcitationCriterion::logdet;
  throw InputError(field, "unknown criterion '" + text + "' (known: condition, logdet)");
}

const char* to_string(LimitKind kind) {
  switch (kind) {
    case LimitKind::lower: return "lower";
    case LimitKind::upper: return "upper";
    case LimitKind::velocity: return "velocity";
    case LimitKind::acceleration: return "acceleration";
  }
  return "unknown";
}

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
  text += ", " + std::to_string(base_parameters) + " base parameters, " + std::to_string(evaluations) +
          " evaluations in " + format_number(wall_seconds) + " s, stopped: " + to_string(termination);
  return text;
}

// ---- Options and limits ----------------------------------------------------------------------

void ExcitationOptions::validate(const Model& model) const { (void)excitation_limits(model, *this); }

ExcitationLimits excitation_limits(const Model& model, const ExcitationOptions& options) {
  const int n = model.joint_count();
  if (n == 0) throw InputError("model", "the model has no moving joint");
  if (!(std::isfinite(options.period) && options.period > 0.0)) {
    throw InputError("period", "the period must be a positive number of seconds, got " + format_number(options.period));
  }
  if (options.harmonics < kMinHarmonics || options.harmonics > kMaxHarmonics) {
    throw InputError("harmonics", "harmonics must lie in " + std::to_string(kMinHarmonics) + ".." +
                                      std::to_string(kMaxHarmonics) + " (got " + std::to_string(options.harmonics) +
                                      "): starting and ending at rest takes one sine and one cosine coefficient "
                                      "per joint, so one harmonic leaves no motion");
  }
  const Eigen::Index given = options.max_acceleration.size();
  if (given != 1 && given != n) {
    throw InputError("max_acceleration", "max_acceleration needs 1 value or one per joint (" + std::to_string(n) +
                                             "), got " + std::to_string(given));
  }
  for (Eigen::Index i = 0; i < given; ++i) {
    const double value = options.max_acceleration[i];
    if (!(std::isfinite(value) && value > 0.0)) {
      throw InputError("max_acceleration", "max_acceleration must be positive and finite, got " + format_number(value));
    }
  }
  if (!(std::isfinite(options.position_margin) && options.position_margin >= 0.0)) {
    throw InputError("position_margin",
                     "position_margin must be a finite number >= 0, got " + format_number(options.position_margin));
  }
  if (options.samples != 0 && (options.samples < 8 * options.harmonics || options.samples > kMaxSamples)) {
    throw InputError("samples", "samples must be 0 (automatic) or lie in " + std::to_string(8 * options.harmonics) +
                                    ".." + std::to_string(kMaxSamples) + " for " + std::to_string(options.harmonics) +
                                    " harmonics (8 per harmonic resolve the regressor's products of harmonics), got " +
                                    std::to_string(options.samples));
  }
  if (options.random_starts < 1) {
    throw InputError("random_starts", "random_starts must be at least 1, got " + std::to_string(options.random_starts));
  }
  if (options.local_starts < 1) {
    throw InputError("local_starts", "local_starts must be at least 1, got " + std::to_string(options.local_starts));
  }
  if (!(options.max_seconds > 0.0) || std::isnan(options.max_seconds)) {
    throw InputError("max_seconds", "max_seconds must be positive, got " + format_number(options.max_seconds));
  }
  if (options.max_evaluations < 1) {
    throw InputError("max_evaluations", "max_evaluations must be at least 1, got " + std::to_string(options.max_evaluations));
  }

  ExcitationLimits limits;
  limits.lower.resize(n);
  limits.upper.resize(n);
  limits.velocity.resize(n);
  limits.acceleration.resize(n);
  for (int k = 0; k < n; ++k) {
    const Joint& joint = model.joints[static_cast<std::size_t>(k)];
    const std::string unit = joint.is_prismatic() ? " m" : " rad";
    limits.lower[k] = joint.limits.lower + options.position_margin;  // ±∞ stays ±∞
    limits.upper[k] = joint.limits.upper - options.position_margin;
    if (!(limits.lower[k] < limits.upper[k])) {
      throw InputError(joint_field(model, k),
                       joint_field(model, k) + ": its range " + format_number(joint.limits.lower) + ".." +
                           format_number(joint.limits.upper) + unit + " leaves no room to move within a margin of " +
                           format_number(options.position_margin) + unit + " on each side");
    }
    limits.velocity[k] = joint.limits.velocity;
    if (!(limits.velocity[k] > 0.0)) {
      throw InputError(joint_field(model, k), joint_field(model, k) + ": its velocity limit is " +
                                                  format_number(limits.velocity[k]) + ", so it cannot move");
    }
    limits.acceleration[k] = options.max_acceleration[given == 1 ? 0 : k];
  }
  return limits;
}

// ---- Design --------------------------------------------------------------------------------

ExcitationDesign design_excitation(const Model& model, const ExcitationOptions& options) {
  const Clock::time_point started = Clock::now();
  const ExcitationLimits limits = excitation_limits(model, options);
  const BaseParameters base = base_parameters(model, options.layout);
  if (base.size() == 0) throw InputError("model", "the model's torques determine no parameter to identify");

  DesignProblem problem(model, options, limits, base);
  Search search;
  search.problem = &problem;
  search.options = &options;
  search.started = started;
  const std::size_t dimension = static_cast<std::size_t>(problem.dimension());

  // Random starts. The first evaluation always runs, so there is a best point to return whatever happens.
  std::mt19937_64 engine(options.seed);
  struct Candidate {
    double cost;
    std::vector<double> x;
  };
  std::vector<Candidate> candidates;
  std::vector<double> x;
  for (int start = 0; start < options.random_starts; ++start) {
    if (start > 0) {
      search.interrupt = search.check();
      if (search.interrupt != Interrupt::none) break;
    }
    problem.random_point(engine, x);
    candidates.push_back({search.evaluate(x.data(), dimension), x});
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  const std::vector<double> start_x = search.best_x;
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
  nlopt::result result = nlopt::SUCCESS;
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
      result = local_search(search, x, failure);
      if (result == nlopt::FAILURE) stopped = true;
      if (result == nlopt::FAILURE || result == nlopt::FORCED_STOP) break;
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
  summary.initial_value = initial_value;
  summary.final_value = search.best_value;
  summary.base_parameters = base.size();
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
      if (result == nlopt::FAILURE) {
        summary.termination = ExcitationTermination::failure;
        summary.message = "NLopt failed (" + failure + "); the best trajectory found is returned";
      } else {
        summary.termination = ExcitationTermination::converged;
        summary.message = "converged: in every local run, a restart no longer improved the criterion";
      }
      break;
  }

  // The figures are reported by SVD (the optimiser saw the faster Gram form).
  design.trajectory = problem.trajectory(start_x.data());
  problem.criterion().stack(design.trajectory.q0, stacked_coefficients(design.trajectory));
  summary.initial_condition_number = problem.criterion().exact_quality().condition_number;
  design.trajectory = problem.trajectory(search.best_x.data());
  problem.criterion().stack(design.trajectory.q0, stacked_coefficients(design.trajectory));
  const ExcitationQuality quality = problem.criterion().exact_quality();
  summary.condition_number = quality.condition_number;
  summary.log_det = quality.log_det;

  Eigen::MatrixXd peaks;
  summary.usage = measured_usage(design.trajectory, limits, peaks);
  for (int k = 0; k < model.joint_count(); ++k) {
    const double bound[4] = {limits.lower[k], limits.upper[k], limits.velocity[k], limits.acceleration[k]};
    for (int kind = 0; kind < 4; ++kind) {
      if (!(summary.usage(k, kind) >= kActiveUsage)) continue;  // NaN (no limit) is never active
      summary.active_limits.push_back(ActiveLimit{k + 1, model.joints[static_cast<std::size_t>(k)].name,
                                                  static_cast<LimitKind>(kind), peaks(k, kind), bound[kind]});
    }
  }
  summary.wall_seconds = std::chrono::duration<double>(Clock::now() - started).count();
  return design;
}

// ---- Sampling, limits, quality -------------------------------------------------------------

void check_sampling(double period, int harmonics, double dt, int periods) {
  if (!(std::isfinite(period) && period > 0.0)) {
    throw InputError("period", "the period must be a positive number of seconds, got " + format_number(period));
  }
  if (periods < 1) throw InputError("periods", "periods must be at least 1, got " + std::to_string(periods));
  if (!(std::isfinite(dt) && dt >= kShortestSamplePeriod && dt <= kLongestSamplePeriod)) {
    throw InputError("dt", "dt must lie in [" + format_number(kShortestSamplePeriod) + ", " +
                               format_number(kLongestSamplePeriod) + "] s, got " + format_number(dt));
  }
  const double ratio = period / dt;
  const double rounded = std::round(ratio);
  if (!(std::abs(ratio - rounded) <= 1e-9 * ratio) || rounded < 1.0) {
    throw InputError("dt", "dt = " + format_number(dt) + " s does not divide the period " + format_number(period) +
                               " s (" + format_number(ratio) +
                               " steps), so the last sample would not fall on the period's end, at rest");
  }
  if (rounded < 4.0 * harmonics) {
    throw InputError("dt", "dt = " + format_number(dt) + " s gives " + format_number(rounded) +
                               " samples per period, fewer than 4 per period of the highest harmonic (" +
                               std::to_string(4 * harmonics) + ")");
  }
  if (rounded * periods + 1.0 > static_cast<double>(kMaxSampledInstants)) {
    throw InputError("dt", "dt = " + format_number(dt) + " s over " + std::to_string(periods) + " period(s) gives " +
                               format_number(rounded * periods + 1.0) + " samples, more than " +
                               std::to_string(kMaxSampledInstants));
  }
}

SampledExcitation sample_excitation(const FourierTrajectory& trajectory, double dt, int periods) {
  trajectory.validate();
  const double T = trajectory.period;
  const int L = trajectory.harmonics();
  check_sampling(T, L, dt, periods);
  const double rounded = std::round(T / dt);
  const long per_period = static_cast<long>(rounded);
  const long instants = per_period * periods + 1;
  const int n = trajectory.joint_count();

  SampledExcitation sampled;
  sampled.t.resize(instants);
  sampled.q.resize(n, instants);
  sampled.qd.resize(n, instants);
  sampled.qdd.resize(n, instants);
  // One period, evaluated term by term in a fixed order — harmonics 2..L, then harmonic 1 — the order in
  // which design_excitation re-imposes the rest conditions (a_k1 = −Σ_{l≥2} a_kl, b_k1 = −Σ_{l≥2} l b_kl).
  // At t = 0 every product is exact (cos 0 = 1, sin 0 = 0), so a designed trajectory's q̇ and q̈ come out
  // exactly 0 there, not ±1e-16. Later periods copy the first: bitwise identical, and exactly at rest at
  // every period's end.
  const double omega = trajectory.angular_frequency();
  Eigen::MatrixXd q(n, per_period), qd(n, per_period), qdd(n, per_period);
  Eigen::VectorXd sines(L), cosines(L);
  for (long j = 0; j < per_period; ++j) {
    for (int l = 1; l <= L; ++l) {
      const long turns = (static_cast<long>(l) * j) % per_period;
      const double phase = kTwoPi * static_cast<double>(turns) / static_cast<double>(per_period);
      sines[l - 1] = std::sin(phase);
      cosines[l - 1] = std::cos(phase);
    }
    for (int k = 0; k < n; ++k) {
      double position = 0.0, velocity = 0.0, acceleration = 0.0;
      for (int step = 0; step < L; ++step) {
        const int l = step + 1 < L ? step + 2 : 1;  // 2, 3, …, L, then 1
        const double a = trajectory.a(k, l - 1), b = trajectory.b(k, l - 1);
        const double s = sines[l - 1], c = cosines[l - 1];
        position += (a * s - b * c) / (omega * l);
        velocity += a * c + b * s;
        acceleration += l * (b * c - a * s);
      }
      q(k, j) = trajectory.q0[k] + position;
      qd(k, j) = velocity;
      qdd(k, j) = omega * acceleration;
    }
  }
  for (long i = 0; i < instants; ++i) {
    const long j = i % per_period;
    sampled.t[i] = T * static_cast<double>(i) / static_cast<double>(per_period);
    sampled.q.col(i) = q.col(j);
    sampled.qd.col(i) = qd.col(j);
    sampled.qdd.col(i) = qdd.col(j);
  }
  return sampled;
}

std::optional<LimitViolation> first_limit_violation(const ExcitationLimits& limits, const SampledExcitation& sampled) {
  const Eigen::Index n = sampled.q.rows();
  if (limits.lower.size() != n || limits.upper.size() != n || limits.velocity.size() != n ||
      limits.acceleration.size() != n || sampled.qd.rows() != n || sampled.qdd.rows() != n ||
      sampled.q.cols() != sampled.t.size() || sampled.qd.cols() != sampled.t.size() ||
      sampled.qdd.cols() != sampled.t.size()) {
    throw InputError("sampled", "the limits and the sampled trajectory have different joint or sample counts");
  }
  // Rounding: a sample computed on the limit may land a few ulps beyond it.
  const auto beyond = [](double value, double limit) { return value > limit + 1e-12 * std::max(1.0, std::abs(limit)); };
  for (Eigen::Index i = 0; i < sampled.t.size(); ++i) {
    for (Eigen::Index k = 0; k < n; ++k) {
      const int joint = static_cast<int>(k) + 1;
      const double q = sampled.q(k, i), qd = std::abs(sampled.qd(k, i)), qdd = std::abs(sampled.qdd(k, i));
      if (!std::isfinite(q) || beyond(-q, -limits.lower[k])) return LimitViolation{joint, LimitKind::lower, sampled.t[i], q, limits.lower[k]};
      if (beyond(q, limits.upper[k])) return LimitViolation{joint, LimitKind::upper, sampled.t[i], q, limits.upper[k]};
      if (!std::isfinite(qd) || beyond(qd, limits.velocity[k])) {
        return LimitViolation{joint, LimitKind::velocity, sampled.t[i], sampled.qd(k, i), limits.velocity[k]};
      }
      if (!std::isfinite(qdd) || beyond(qdd, limits.acceleration[k])) {
        return LimitViolation{joint, LimitKind::acceleration, sampled.t[i], sampled.qdd(k, i), limits.acceleration[k]};
      }
    }
  }
  return std::nullopt;
}

ExcitationQuality excitation_quality(const Model& model, const FourierTrajectory& trajectory,
                                     const ExcitationOptions& options) {
  trajectory.validate();
  if (trajectory.joint_count() != model.joint_count()) {
    throw InputError("q0", "the trajectory has " + std::to_string(trajectory.joint_count()) + " joints, the model " +
                               std::to_string(model.joint_count()));
  }
  const int L = trajectory.harmonics();
  const int samples = options.samples > 0 ? options.samples : std::max(200, 40 * L);
  if (samples < 8 * L || samples > kMaxSamples) {
    throw InputError("samples", "samples must be 0 (automatic) or lie in " + std::to_string(8 * L) + ".." +
                                    std::to_string(kMaxSamples) + " for " + std::to_string(L) + " harmonics");
  }
  const BaseParameters base = base_parameters(model, options.layout);
  CriterionWorkspace workspace(model, options.layout, base, trajectory.period, L, samples);
  workspace.stack(trajectory.q0, stacked_coefficients(trajectory));
  return workspace.exact_quality();
}

int whole_periods(double duration, double period) {
  const double ratio = duration / period;
  const double periods = std::round(ratio);
  if (!(periods >= 1.0) || std::abs(ratio - periods) > 1e-9 * ratio || periods > 1e6) {
    std::ostringstream message;
    message << "duration " << duration << " s is not a whole number of periods (period " << period
            << " s): the trajectory ends at rest only after whole periods";
    throw InputError("duration", message.str());
  }
  return static_cast<int>(periods);
}

Trajectory to_trajectory(const SampledExcitation& sampled) {
  Trajectory trajectory;
  trajectory.t = sampled.t;
  trajectory.q = sampled.q.transpose();
  trajectory.qd = sampled.qd.transpose();
  trajectory.qdd = sampled.qdd.transpose();
  return trajectory;
}

}  // namespace manipid::robot

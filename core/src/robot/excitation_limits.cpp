// excitation_limits.cpp — the excitation's limits: the options checked and the limits resolved per joint,
// the grid bound that keeps them for every t, the largest scale of a joint's motion within them, and the
// checks of a sampled or designed trajectory against them (robot/excitation.h).
//
// The limits hold for every t, not only on the grid where they are checked. On a grid of spacing h, a
// smooth periodic f with |f''| ≤ M has max_t f ≤ max_grid f + h² M / 8 (at the true maximum f' = 0, and
// the nearest grid point is at most h/2 away). For a harmonic of amplitude r at frequency ω l, |f''| ≤
// r (ω l)², so M ≤ Σ_l r_l (ω l)² is known from the coefficients. The grid has 64 points per period of the
// highest harmonic — 32 times its Nyquist rate — so the bound costs at most (2π/64)²/8 ≈ 0.12 % of the
// room, and a trajectory sampled at any step (the command's dt) stays inside. The jerk likewise, with
// M ≤ Σ_l r_l (ω l)⁴.
//
// The torque is not linear in the coefficients, so it cannot be scaled joint by joint: TorqueGuard scales
// every joint's motion about q0 by one factor γ, found by regula falsi (Illinois) on the largest ratio of
// torque to limit at the criterion's instants.
#include "robot/excitation_internal.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/rnea.h"
#include "numbers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

namespace manipid::robot {
namespace {

using detail::format_number;
using detail::kMaxHarmonics;
using detail::kMaxSamples;
using detail::kMinHarmonics;
using manipid::detail::kInfinity;

std::string joint_field(const Model& model, int k) { return "joint " + model.joints[static_cast<std::size_t>(k)].name; }

/// The smallest velocity, acceleration, jerk or torque limit accepted: below it nothing moves measurably.
constexpr double kSmallestLimit = 1e-3;

/// Per-joint limits given as nothing, one value for every joint, or one per joint: each positive and finite.
/// Returns n values (+∞ where none was given).
Eigen::VectorXd per_joint(const Eigen::VectorXd& given, int n, const std::string& field, const std::string& unit) {
  if (given.size() != 0 && given.size() != 1 && given.size() != n) {
    throw InputError(field, field + " needs 1 value or one per joint (" + std::to_string(n) + "), got " +
                                std::to_string(given.size()));
  }
  for (Eigen::Index i = 0; i < given.size(); ++i) {
    if (!(std::isfinite(given[i]) && given[i] > 0.0)) {
      throw InputError(field, field + " must be positive and finite, " + unit + ", got " + format_number(given[i]));
    }
    // 1e-300 rad/s² "succeeded" with a motionless trajectory and a condition number of ∞.
    if (given[i] < kSmallestLimit) {
      throw InputError(field, field + " of " + format_number(given[i]) + " " + unit +
                                  " leaves a joint no motion to measure; give at least " + format_number(kSmallestLimit));
    }
  }
  if (given.size() == 0) return Eigen::VectorXd::Constant(n, kInfinity);
  if (given.size() == 1) return Eigen::VectorXd::Constant(n, given[0]);
  return given;
}

}  // namespace

namespace detail {

using manipid::detail::kInfinity;

LimitGrid::LimitGrid(double period, int harmonics)
    : harmonics_(harmonics),
      omega_(kTwoPi / period),
      spacing_(period / (kConstraintPointsPerHarmonic * harmonics)),
      table_(period, harmonics, kConstraintPointsPerHarmonic * harmonics, Instants::starts) {}

void LimitGrid::peaks(const Eigen::MatrixXd& K, Eigen::MatrixXd& work, std::vector<Peaks>& out) const {
  const Eigen::Index n = K.rows();
  out.resize(static_cast<std::size_t>(n));
  const double h2 = spacing_ * spacing_ / 8.0;
  // Curvature bounds: Σ_l r_l (ω l)^m for m = 1 (position's f'' is q̈), 2 (q̇), 3 (q̈), 4 (jerk).
  for (Eigen::Index k = 0; k < n; ++k) {
    double m1 = 0.0, m2 = 0.0, m3 = 0.0, m4 = 0.0;
    for (int l = 1; l <= harmonics_; ++l) {
      const double r = std::hypot(K(k, l - 1), K(k, harmonics_ + l - 1));
      const double w = omega_ * l;
      m1 += r * w;
      m2 += r * w * w;
      m3 += r * w * w * w;
      m4 += r * w * w * w * w;
    }
    Peaks& p = out[static_cast<std::size_t>(k)];
    p.highest = h2 * m1;
    p.lowest = -h2 * m1;
    p.velocity = h2 * m2;
    p.acceleration = h2 * m3;
    p.jerk = h2 * m4;
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
  work.noalias() = K * table_.jerk;
  for (Eigen::Index k = 0; k < n; ++k) out[static_cast<std::size_t>(k)].jerk += work.row(k).cwiseAbs().maxCoeff();
}

double largest_scale(const Peaks& peaks, double q0, const ExcitationLimits& limits, Eigen::Index k) {
  double s = kInfinity;
  const auto within = [&s](double limit, double peak) {
    if (std::isfinite(limit) && peak > 0.0) s = std::min(s, limit / peak);
  };
  within(limits.velocity[k], peaks.velocity);
  within(limits.acceleration[k], peaks.acceleration);
  within(limits.jerk[k], peaks.jerk);
  within(limits.upper[k] - q0, peaks.highest);
  within(q0 - limits.lower[k], -peaks.lowest);
  // No motion at all (every coefficient 0) leaves s infinite: nothing to scale.
  return std::isfinite(s) ? std::max(s, 0.0) : 0.0;
}

TorqueGuard::TorqueGuard(const Model& model, const ExcitationLimits& limits, double period, int harmonics,
                         int instants)
    : model_(model),
      limits_(limits),
      table_(period, harmonics, instants, Instants::midpoints),
      data_(model),
      q0_(model.joint_count()),
      q_(model.joint_count()),
      qd_(model.joint_count()),
      qdd_(model.joint_count()),
      tau_(model.joint_count()) {}

double TorqueGuard::ratio(double gamma) {
  const Eigen::Index n = q0_.size();
  double worst = 0.0;
  // At rest (γ = 0) every instant is the same pose: one is enough.
  const Eigen::Index instants = gamma == 0.0 ? std::min<Eigen::Index>(1, p_.cols()) : p_.cols();
  for (Eigen::Index j = 0; j < instants; ++j) {
    q_ = q0_ + gamma * p_.col(j);
    qd_ = gamma * v_.col(j);
    qdd_ = gamma * a_.col(j);
    inverse_dynamics(model_, data_, limits_.torque_layout, limits_.torque_parameters, q_, qd_, qdd_, tau_);
    for (Eigen::Index k = 0; k < n; ++k) {
      if (std::isfinite(limits_.torque[k])) worst = std::max(worst, std::abs(tau_[k]) / (kTorqueShare * limits_.torque[k]));
    }
    if (!std::isfinite(tau_.sum())) return kInfinity;
  }
  return worst;
}

double TorqueGuard::largest_factor(const Eigen::VectorXd& q0, const Eigen::MatrixXd& K) {
  q0_ = q0;
  p_.noalias() = K * table_.position;
  v_.noalias() = K * table_.velocity;
  a_.noalias() = K * table_.acceleration;
  double high = 1.0, f_high = ratio(1.0) - 1.0;
  if (f_high <= 0.0) return 1.0;
  // At rest at q0 (γ = 0): with Coulomb friction's sign(0) = 0, only gravity and the offset.
  double low = 0.0, f_low = ratio(0.0) - 1.0;
  if (f_low > 0.0) return -1.0;
  if (!std::isfinite(f_high)) f_high = 1e6;
  // Regula falsi with the Illinois rule: f(γ) = ratio − 1 changes sign on [low, high]; low stays feasible.
  int side = 0;
  for (int iteration = 0; iteration < 30 && high - low > 5e-3 * high; ++iteration) {
    double gamma = (low * f_high - high * f_low) / (f_high - f_low);
    gamma = std::clamp(gamma, low + 0.01 * (high - low), high - 0.01 * (high - low));
    const double f = ratio(gamma) - 1.0;
    if (f <= 0.0) {
      low = gamma;
      f_low = f;
      if (side == -1) f_high *= 0.5;
      side = -1;
    } else {
      high = gamma;
      f_high = std::isfinite(f) ? f : 1e6;
      if (side == +1) f_low *= 0.5;
      side = +1;
    }
  }
  return low;
}

Eigen::MatrixXd measured_usage(const Model& model, const FourierTrajectory& trajectory, const ExcitationLimits& limits,
                               Eigen::MatrixXd& peaks) {
  const int n = trajectory.joint_count();
  const int points = 4 * kConstraintPointsPerHarmonic * trajectory.harmonics();
  const HarmonicTable table(trajectory.period, trajectory.harmonics(), points, Instants::starts);
  const Eigen::MatrixXd K = stacked_coefficients(trajectory);
  const Eigen::MatrixXd p = K * table.position, v = K * table.velocity, a = K * table.acceleration,
                        j = K * table.jerk;
  // The torque on the same grid, with the limits' model.
  Data data(model);
  Eigen::VectorXd tau(n), tau_peak = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < points; ++i) {
    inverse_dynamics(model, data, limits.torque_layout, limits.torque_parameters, trajectory.q0 + p.col(i), v.col(i),
                     a.col(i), tau);
    tau_peak = tau_peak.cwiseMax(tau.cwiseAbs());
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Eigen::MatrixXd usage = Eigen::MatrixXd::Constant(n, kLimitKinds, nan);
  peaks.resize(n, kLimitKinds);
  for (int k = 0; k < n; ++k) {
    const double q0 = trajectory.q0[k];
    peaks(k, 0) = q0 + p.row(k).minCoeff();
    peaks(k, 1) = q0 + p.row(k).maxCoeff();
    peaks(k, 2) = v.row(k).cwiseAbs().maxCoeff();
    peaks(k, 3) = a.row(k).cwiseAbs().maxCoeff();
    peaks(k, 4) = j.row(k).cwiseAbs().maxCoeff();
    peaks(k, 5) = tau_peak[k];
    if (std::isfinite(limits.lower[k])) {
      usage(k, 0) = q0 > limits.lower[k] ? (q0 - peaks(k, 0)) / (q0 - limits.lower[k]) : 1.0;
    }
    if (std::isfinite(limits.upper[k])) {
      usage(k, 1) = q0 < limits.upper[k] ? (peaks(k, 1) - q0) / (limits.upper[k] - q0) : 1.0;
    }
    const double rates[4] = {limits.velocity[k], limits.acceleration[k], limits.jerk[k], limits.torque[k]};
    for (int kind = 2; kind < kLimitKinds; ++kind) {
      if (std::isfinite(rates[kind - 2])) usage(k, kind) = peaks(k, kind) / rates[kind - 2];
    }
  }
  return usage;
}

}  // namespace detail

const char* to_string(LimitKind kind) {
  switch (kind) {
    case LimitKind::lower: return "lower";
    case LimitKind::upper: return "upper";
    case LimitKind::velocity: return "velocity";
    case LimitKind::acceleration: return "acceleration";
    case LimitKind::jerk: return "jerk";
    case LimitKind::torque: return "torque";
  }
  return "unknown";
}

bool ExcitationLimits::any_torque() const { return torque.size() > 0 && torque.array().isFinite().any(); }

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
  if (options.max_acceleration.size() == 0) {
    throw InputError("max_acceleration", "max_acceleration needs 1 value or one per joint (" + std::to_string(n) + "), got 0");
  }
  const Eigen::VectorXd acceleration = per_joint(options.max_acceleration, n, "max_acceleration", "rad/s^2");
  const Eigen::VectorXd velocity = per_joint(options.max_velocity, n, "max_velocity", "rad/s");
  const Eigen::VectorXd jerk = per_joint(options.max_jerk, n, "max_jerk", "rad/s^3");
  const Eigen::VectorXd torque = per_joint(options.max_torque, n, "max_torque", "N m");
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
  std::vector<bool> moving(static_cast<std::size_t>(n), false);
  for (int k : options.moving_joints) {
    if (k < 0 || k >= n) {
      throw InputError("moving_joints", "joint " + std::to_string(k + 1) + " is not one of the robot's " + std::to_string(n));
    }
    if (moving[static_cast<std::size_t>(k)]) {
      throw InputError("moving_joints", "joint " + std::to_string(k + 1) + " (" + model.joints[static_cast<std::size_t>(k)].name +
                                            ") is named twice");
    }
    moving[static_cast<std::size_t>(k)] = true;
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
  limits.acceleration = acceleration;
  limits.jerk = jerk;
  limits.torque.resize(n);
  limits.torque_layout = options.torque_layout;
  if (options.torque_parameters.size() == 0) {
    limits.torque_parameters = standard_parameters(model, options.torque_layout);
  } else {
    const int expected = options.torque_layout.size(n);
    if (options.torque_parameters.size() != expected || !options.torque_parameters.allFinite()) {
      throw InputError("torque_parameters", "the torque model needs " + std::to_string(expected) +
                                                " finite standard parameters for its layout, got " +
                                                std::to_string(options.torque_parameters.size()));
    }
    limits.torque_parameters = options.torque_parameters;
  }
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
    limits.velocity[k] = std::min(joint.limits.velocity, velocity[k]);
    if (!(limits.velocity[k] > 0.0)) {
      throw InputError(joint_field(model, k), joint_field(model, k) + ": its velocity limit is " +
                                                  format_number(limits.velocity[k]) + ", so it cannot move");
    }
    // An effort of 0 is urdfdom's value for a <limit> without one: no torque limit, not a joint that
    // cannot push.
    const double effort = joint.limits.effort > 0.0 ? joint.limits.effort : kInfinity;
    limits.torque[k] = std::min(effort, torque[k]);
  }
  if (options.start_pose.size() != 0) {
    if (options.start_pose.size() != n) {
      throw InputError("start_pose", "start_pose needs one value per joint (" + std::to_string(n) + "), got " +
                                         std::to_string(options.start_pose.size()));
    }
    for (int k = 0; k < n; ++k) {
      const Joint& joint = model.joints[static_cast<std::size_t>(k)];
      const double q = options.start_pose[k];
      if (!(std::isfinite(q) && q >= joint.limits.lower && q <= joint.limits.upper)) {
        throw InputError("start_pose", "the start pose puts joint " + std::to_string(k + 1) + " (" + joint.name + ") at " +
                                           format_number(q) + (joint.is_prismatic() ? " m" : " rad") +
                                           ", outside its URDF limits " + format_number(joint.limits.lower) + ".." +
                                           format_number(joint.limits.upper));
      }
    }
  }
  return limits;
}

// ---- Checks ----------------------------------------------------------------------------------

std::string describe(const LimitViolation& violation) {
  const bool position = violation.kind == LimitKind::lower || violation.kind == LimitKind::upper;
  return std::string("the ") + to_string(violation.kind) + (position ? " position" : "") + " limit of joint " +
         std::to_string(violation.joint) + " (" + format_number(violation.limit) + ") at t = " +
         format_number(violation.t) + " s: " + format_number(violation.value);
}

std::optional<LimitViolation> first_limit_violation(const ExcitationLimits& limits, const SampledExcitation& sampled,
                                                    const Model* model) {
  const Eigen::Index n = sampled.q.rows();
  // Limits built by hand before jerk and torque existed leave them empty: none.
  const bool has_jerk = sampled.jerk.size() > 0 && limits.jerk.size() != 0;
  if (limits.lower.size() != n || limits.upper.size() != n || limits.velocity.size() != n ||
      limits.acceleration.size() != n || (limits.jerk.size() != 0 && limits.jerk.size() != n) ||
      (limits.torque.size() != 0 && limits.torque.size() != n) ||
      sampled.qd.rows() != n || sampled.qdd.rows() != n || sampled.q.cols() != sampled.t.size() ||
      sampled.qd.cols() != sampled.t.size() || sampled.qdd.cols() != sampled.t.size() ||
      (has_jerk && (sampled.jerk.rows() != n || sampled.jerk.cols() != sampled.t.size())) ||
      (model && model->joint_count() != n)) {
    throw InputError("sampled", "the limits and the sampled trajectory have different joint or sample counts");
  }
  std::optional<Data> data;
  Eigen::VectorXd tau(n);
  if (model && limits.any_torque()) data.emplace(*model);
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
      if (has_jerk && (!std::isfinite(sampled.jerk(k, i)) || beyond(std::abs(sampled.jerk(k, i)), limits.jerk[k]))) {
        return LimitViolation{joint, LimitKind::jerk, sampled.t[i], sampled.jerk(k, i), limits.jerk[k]};
      }
    }
    if (data) {
      inverse_dynamics(*model, *data, limits.torque_layout, limits.torque_parameters, sampled.q.col(i), sampled.qd.col(i),
                       sampled.qdd.col(i), tau);
      for (Eigen::Index k = 0; k < n; ++k) {
        if (!std::isfinite(tau[k]) || beyond(std::abs(tau[k]), limits.torque[k])) {
          return LimitViolation{static_cast<int>(k) + 1, LimitKind::torque, sampled.t[i], tau[k], limits.torque[k]};
        }
      }
    }
  }
  return std::nullopt;
}

}  // namespace manipid::robot

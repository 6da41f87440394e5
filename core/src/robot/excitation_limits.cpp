// excitation_limits.cpp — the excitation's limits: the options checked and the limits resolved per joint,
// the grid bound that keeps them for every t, the largest scale of a joint's motion within them, and the
// checks of a sampled or designed trajectory against them (robot/excitation.h).
//
// The limits hold for every t, not only on the grid where they are checked. On a grid of spacing h, a
// smooth periodic f with |f''| ≤ M has max_t f ≤ max_grid f + h² M / 8 (at the true maximum f' = 0, and
// the nearest grid point is at most h/2 away). For a harmonic of amplitude r at frequency ω l, |f''| ≤
// r (ω l)², so M ≤ Σ_l r_l (ω l)² is known from the coefficients. The grid has 64 points per period of the
// highest harmonic — 32 times its Nyquist rate — so the bound costs at most (2π/64)²/8 ≈ 0.12 % of the
// room, and a trajectory sampled at any step (the command's dt) stays inside.
#include "robot/excitation_internal.h"

#include "manipid/core/errors.h"
#include "numbers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace manipid::robot {
namespace {

using detail::format_number;
using detail::kMaxHarmonics;
using detail::kMaxSamples;
using detail::kMinHarmonics;

std::string joint_field(const Model& model, int k) { return "joint " + model.joints[static_cast<std::size_t>(k)].name; }

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

double largest_scale(const Peaks& peaks, double q0, double lower, double upper, double velocity, double acceleration) {
  double s = kInfinity;
  if (std::isfinite(velocity) && peaks.velocity > 0.0) s = std::min(s, velocity / peaks.velocity);
  if (peaks.acceleration > 0.0) s = std::min(s, acceleration / peaks.acceleration);
  if (std::isfinite(upper) && peaks.highest > 0.0) s = std::min(s, (upper - q0) / peaks.highest);
  if (std::isfinite(lower) && peaks.lowest < 0.0) s = std::min(s, (q0 - lower) / -peaks.lowest);
  // No motion at all (every coefficient 0) leaves s infinite: nothing to scale.
  return std::isfinite(s) ? std::max(s, 0.0) : 0.0;
}

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

}  // namespace detail

const char* to_string(LimitKind kind) {
  switch (kind) {
    case LimitKind::lower: return "lower";
    case LimitKind::upper: return "upper";
    case LimitKind::velocity: return "velocity";
    case LimitKind::acceleration: return "acceleration";
  }
  return "unknown";
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

// ---- Checks ----------------------------------------------------------------------------------

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

}  // namespace manipid::robot

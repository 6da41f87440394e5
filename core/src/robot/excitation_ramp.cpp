// excitation_ramp.cpp — the excitation's start pose: the quintic ramp from where the arm stands to the
// series' start and back, its shortest duration within every limit (the torque's included), and the
// design sampled with it (robot/excitation.h's file comment).
#include "robot/excitation_internal.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/rnea.h"
#include "numbers.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace manipid::robot {
namespace {

using detail::format_number;
using manipid::detail::kInfinity;

/// The quintic rest-to-rest profile s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ on τ ∈ [0, 1] and its derivatives in τ.
struct Quintic {
  double s, ds, dds, ddds;
  explicit Quintic(double tau)
      : s(tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau))),
        ds(30.0 * tau * tau * (1.0 - tau) * (1.0 - tau)),
        dds(60.0 * tau * (1.0 + tau * (-3.0 + 2.0 * tau))),
        ddds(60.0 + tau * (-360.0 + 360.0 * tau)) {}
};
/// max |s'|, |s''|, |s'''| over [0, 1]: at τ = ½, (3 − √3)/6 and 0.
constexpr double kPeakRate = 1.875;
const double kPeakAcceleration = 10.0 / std::sqrt(3.0);
constexpr double kPeakJerk = 60.0;

/// Instants at which the ramp's torque is checked (the profile's spectrum is a few cycles over D).
constexpr int kRampChecks = 400;
/// How far D grows per try while the torque exceeds a limit along the ramp, and the longest ramp offered:
/// a torque that still exceeds a limit after two minutes of creeping is the pose's, not the speed's.
constexpr double kRampGrowth = 1.1;
constexpr double kLongestRamp = 120.0;  // s

std::string joint_label(const Model& model, Eigen::Index k) {
  return "joint " + std::to_string(k + 1) + " (" + model.joints[static_cast<std::size_t>(k)].name + ")";
}

/// The arm at rest at q: a joint whose torque leaves its limit, named, with the torque.
void check_at_rest(const Model& model, Data& data, const ExcitationLimits& limits, const Eigen::VectorXd& q,
                   const std::string& where) {
  const Eigen::Index n = q.size();
  Eigen::VectorXd tau(n);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  inverse_dynamics(model, data, limits.torque_layout, limits.torque_parameters, q, zero, zero, tau);
  for (Eigen::Index k = 0; k < n; ++k) {
    if (std::abs(tau[k]) > limits.torque[k]) {
      throw InputError("start_pose", joint_label(model, k) + " needs " + format_number(std::abs(tau[k])) +
                                         " N m to hold the arm still at " + where + ", beyond its torque limit " +
                                         format_number(limits.torque[k]) + " N m");
    }
  }
}

/// The largest |τ_k| along the ramp of duration D, per joint.
Eigen::VectorXd ramp_torque(const Model& model, Data& data, const ExcitationLimits& limits, const Eigen::VectorXd& pose,
                            const Eigen::VectorXd& delta, double D) {
  const Eigen::Index n = pose.size();
  Eigen::VectorXd tau(n), peak = Eigen::VectorXd::Zero(n);
  for (int i = 0; i <= kRampChecks; ++i) {
    const Quintic profile(static_cast<double>(i) / kRampChecks);
    inverse_dynamics(model, data, limits.torque_layout, limits.torque_parameters, pose + profile.s * delta,
                     (profile.ds / D) * delta, (profile.dds / (D * D)) * delta, tau);
    peak = peak.cwiseMax(tau.cwiseAbs());
  }
  return peak;
}

}  // namespace

StartRamp plan_ramp(const Model& model, const ExcitationLimits& limits, const Eigen::VectorXd& pose,
                    const Eigen::VectorXd& target) {
  const int n = model.joint_count();
  if (pose.size() != n || target.size() != n || !pose.allFinite() || !target.allFinite()) {
    throw InputError("start_pose", "start_pose needs " + std::to_string(n) + " finite values");
  }
  StartRamp ramp;
  ramp.pose = pose;
  ramp.target = target;
  const Eigen::VectorXd delta = target - pose;
  // The shortest D for the kinematic limits, joint by joint: peak = Δ · (profile's peak) / D^m.
  double D = 0.0;
  for (int k = 0; k < n; ++k) {
    const double distance = std::abs(delta[k]);
    if (distance == 0.0) continue;
    if (std::isfinite(limits.velocity[k])) D = std::max(D, kPeakRate * distance / limits.velocity[k]);
    D = std::max(D, std::sqrt(kPeakAcceleration * distance / limits.acceleration[k]));
    if (std::isfinite(limits.jerk[k])) D = std::max(D, std::cbrt(kPeakJerk * distance / limits.jerk[k]));
  }
  Data data(model);
  Eigen::VectorXd torque = Eigen::VectorXd::Zero(n);
  if (limits.any_torque()) {
    check_at_rest(model, data, limits, pose, "the start pose");
    check_at_rest(model, data, limits, target, "the excitation's start");
  }
  if (D > 0.0) {
    torque = ramp_torque(model, data, limits, pose, delta, D);
    while (limits.any_torque() && !(torque.array() <= limits.torque.array()).all()) {
      if (D * kRampGrowth > kLongestRamp) {
        Eigen::Index worst = 0;
        (torque.array() / limits.torque.array()).maxCoeff(&worst);
        throw InputError("start_pose", "the ramp from the start pose to the excitation's start needs " +
                                           format_number(torque[worst]) + " N m at " + joint_label(model, worst) +
                                           " however slow it is, beyond its torque limit " +
                                           format_number(limits.torque[worst]) + " N m: choose another start pose");
      }
      D *= kRampGrowth;
      torque = ramp_torque(model, data, limits, pose, delta, D);
    }
  }
  ramp.duration = D;
  ramp.peaks = Eigen::MatrixXd::Zero(n, 4);
  if (D > 0.0) {
    const Eigen::VectorXd distance = delta.cwiseAbs();
    ramp.peaks.col(0) = distance * (kPeakRate / D);
    ramp.peaks.col(1) = distance * (kPeakAcceleration / (D * D));
    ramp.peaks.col(2) = distance * (kPeakJerk / (D * D * D));
    ramp.peaks.col(3) = torque;
  }
  return ramp;
}

SampledExcitation sample_excitation(const ExcitationDesign& design, double dt, int periods) {
  SampledExcitation series = sample_excitation(design.trajectory, dt, periods);
  if (!design.ramp || !(design.ramp->duration > 0.0)) return series;
  const StartRamp& ramp = *design.ramp;
  const Eigen::Index n = series.q.rows();
  // Whole steps, so the series starts on a sample (a longer ramp keeps every limit: its peaks fall with D).
  const long steps = std::max(1L, static_cast<long>(std::ceil(ramp.duration / dt - 1e-9)));
  const double D = static_cast<double>(steps) * dt;
  const Eigen::Index count = series.t.size() + 2 * steps;
  if (count > detail::kMaxSampledInstants) {
    throw InputError("dt", "the ramps of " + format_number(D) + " s from the start pose and back, at dt = " +
                               format_number(dt) + " s, make " + std::to_string(count) + " samples in all, more than " +
                               std::to_string(detail::kMaxSampledInstants));
  }
  SampledExcitation sampled;
  sampled.ramp_duration = D;
  sampled.t.resize(count);
  sampled.q.resize(n, count);
  sampled.qd.resize(n, count);
  sampled.qdd.resize(n, count);
  sampled.jerk.resize(n, count);
  const Eigen::VectorXd delta = ramp.target - ramp.pose;
  const double end = D + series.t[series.t.size() - 1];
  for (long i = 0; i < steps; ++i) {
    // In: pose → target over [0, D); out: target → pose over (end, end + D], the same profile reversed.
    const Quintic profile(static_cast<double>(i) / static_cast<double>(steps));
    const Eigen::Index in = i, out = count - 1 - i;
    sampled.t[in] = static_cast<double>(i) * dt;
    sampled.q.col(in) = ramp.pose + profile.s * delta;
    sampled.qd.col(in) = (profile.ds / D) * delta;
    sampled.qdd.col(in) = (profile.dds / (D * D)) * delta;
    sampled.jerk.col(in) = (profile.ddds / (D * D * D)) * delta;
    sampled.t[out] = end + static_cast<double>(steps - i) * dt;
    sampled.q.col(out) = sampled.q.col(in);
    sampled.qd.col(out) = -sampled.qd.col(in);
    sampled.qdd.col(out) = sampled.qdd.col(in);
    sampled.jerk.col(out) = -sampled.jerk.col(in);
  }
  sampled.t.segment(steps, series.t.size()) = series.t.array() + D;
  sampled.q.middleCols(steps, series.t.size()) = series.q;
  sampled.qd.middleCols(steps, series.t.size()) = series.qd;
  sampled.qdd.middleCols(steps, series.t.size()) = series.qdd;
  sampled.jerk.middleCols(steps, series.t.size()) = series.jerk;
  return sampled;
}

}  // namespace manipid::robot

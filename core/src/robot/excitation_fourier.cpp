// excitation_fourier.cpp — the excitation's series: a FourierTrajectory's start and checks, the Fourier basis
// on a grid of one period, and the sampled trajectory (robot/excitation.h; the series in its file comment).
#include "robot/excitation_internal.h"

#include "manipid/core/errors.h"
#include "manipid/core/signal/trajectory.h"

#include <cmath>
#include <sstream>
#include <string>

namespace manipid::robot {
namespace {

using detail::format_number;
using detail::kTwoPi;

using detail::kMaxSampledInstants;

}  // namespace

namespace detail {

HarmonicTable::HarmonicTable(double period, int harmonics, int instants, Instants where) {
  const int L = harmonics;
  const double omega = kTwoPi / period;
  const long steps = 2 * static_cast<long>(instants);
  position.resize(2 * L, instants);
  velocity.resize(2 * L, instants);
  acceleration.resize(2 * L, instants);
  jerk.resize(2 * L, instants);
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
      jerk(l - 1, j) = -w * w * c;
      jerk(L + l - 1, j) = -w * w * s;
    }
  }
}

Eigen::MatrixXd stacked_coefficients(const FourierTrajectory& trajectory) {
  Eigen::MatrixXd K(trajectory.joint_count(), 2 * trajectory.harmonics());
  K << trajectory.a, trajectory.b;
  return K;
}

}  // namespace detail

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

// ---- Sampling --------------------------------------------------------------------------------

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
  sampled.jerk.resize(n, instants);
  // One period, evaluated term by term in a fixed order — harmonics 2..L, then harmonic 1 — the order in
  // which design_excitation re-imposes the rest conditions (a_k1 = −Σ_{l≥2} a_kl, b_k1 = −Σ_{l≥2} l b_kl).
  // At t = 0 every product is exact (cos 0 = 1, sin 0 = 0), so a designed trajectory's q̇ and q̈ come out
  // exactly 0 there, not ±1e-16. Later periods copy the first: bitwise identical, and exactly at rest at
  // every period's end.
  const double omega = trajectory.angular_frequency();
  Eigen::MatrixXd q(n, per_period), qd(n, per_period), qdd(n, per_period), jerk(n, per_period);
  Eigen::VectorXd sines(L), cosines(L);
  for (long j = 0; j < per_period; ++j) {
    for (int l = 1; l <= L; ++l) {
      const long turns = (static_cast<long>(l) * j) % per_period;
      const double phase = kTwoPi * static_cast<double>(turns) / static_cast<double>(per_period);
      sines[l - 1] = std::sin(phase);
      cosines[l - 1] = std::cos(phase);
    }
    for (int k = 0; k < n; ++k) {
      double position = 0.0, velocity = 0.0, acceleration = 0.0, third = 0.0;
      for (int step = 0; step < L; ++step) {
        const int l = step + 1 < L ? step + 2 : 1;  // 2, 3, …, L, then 1
        const double a = trajectory.a(k, l - 1), b = trajectory.b(k, l - 1);
        const double s = sines[l - 1], c = cosines[l - 1];
        position += (a * s - b * c) / (omega * l);
        velocity += a * c + b * s;
        acceleration += l * (b * c - a * s);
        third -= static_cast<double>(l) * l * (a * c + b * s);
      }
      q(k, j) = trajectory.q0[k] + position;
      qd(k, j) = velocity;
      qdd(k, j) = omega * acceleration;
      jerk(k, j) = omega * omega * third;
    }
  }
  for (long i = 0; i < instants; ++i) {
    const long j = i % per_period;
    sampled.t[i] = T * static_cast<double>(i) / static_cast<double>(per_period);
    sampled.q.col(i) = q.col(j);
    sampled.qd.col(i) = qd.col(j);
    sampled.qdd.col(i) = qdd.col(j);
    sampled.jerk.col(i) = jerk.col(j);
  }
  return sampled;
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

// simulated_runs.h — robot test runs made by inverse dynamics: a random Fourier motion or a designed excitation, τ = RNEA(π) along it, a perturbed truth.
#pragma once

#include "manipid/core/robot/data.h"
#include "manipid/core/robot/excitation.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <cmath>
#include <numbers>
#include <random>

namespace manipid::robot::testing {

/// A finite Fourier series per joint (Swevers' form): q_k(t) = Σ_l a_kl/(ω l) sin(ω l t) − b_kl/(ω l) cos(ω l t).
struct Fourier {
  double period = 10.0;
  Eigen::MatrixXd a, b;  // n × harmonics

  static Fourier random(int n, int harmonics, std::mt19937_64& engine, double amplitude = 0.25) {
    std::uniform_real_distribution<double> uniform(-amplitude, amplitude);
    Fourier f;
    f.a.resize(n, harmonics);
    f.b.resize(n, harmonics);
    for (int k = 0; k < n; ++k) {
      for (int l = 0; l < harmonics; ++l) {
        f.a(k, l) = uniform(engine);
        f.b(k, l) = uniform(engine);
      }
    }
    return f;
  }
  void state(double t, Eigen::VectorXd& q, Eigen::VectorXd& qd, Eigen::VectorXd& qdd) const {
    const double w0 = 2.0 * std::numbers::pi / period;
    q.setZero(a.rows());
    qd.setZero(a.rows());
    qdd.setZero(a.rows());
    for (Eigen::Index l = 0; l < a.cols(); ++l) {
      const double w = w0 * static_cast<double>(l + 1), s = std::sin(w * t), c = std::cos(w * t);
      q += (a.col(l) * s - b.col(l) * c) / w;
      qd += a.col(l) * c + b.col(l) * s;
      qdd += (-a.col(l) * s + b.col(l) * c) * w;
    }
  }
};

/// τ = RNEA(π) sampled at the given times along the trajectory.
inline Trajectory measure(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi, const Fourier& motion,
                   const Eigen::VectorXd& times) {
  const int n = model.joint_count();
  Trajectory data;
  data.t = times;
  data.q.resize(times.size(), n);
  data.tau.resize(times.size(), n);
  Data workspace(model);
  Eigen::VectorXd q, qd, qdd, tau(n);
  for (Eigen::Index s = 0; s < times.size(); ++s) {
    motion.state(times[s], q, qd, qdd);
    inverse_dynamics(model, workspace, layout, pi, q, qd, qdd, tau);
    data.q.row(s) = q.transpose();
    data.tau.row(s) = tau.transpose();
  }
  return data;
}

/// τ = RNEA(π) along a designed excitation, sampled at dt.
inline Trajectory measure_excitation(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi,
                              const FourierTrajectory& trajectory, double dt, int periods) {
  const SampledExcitation sampled = sample_excitation(trajectory, dt, periods);
  Trajectory data = to_trajectory(sampled);
  data.tau.resize(data.samples(), model.joint_count());
  Data workspace(model);
  Eigen::VectorXd tau(model.joint_count());
  for (Eigen::Index s = 0; s < data.t.size(); ++s) {
    inverse_dynamics(model, workspace, layout, pi, sampled.q.col(s), sampled.qd.col(s), sampled.qdd.col(s), tau);
    data.tau.row(s) = tau.transpose();
  }
  return data;
}

inline Eigen::VectorXd uniform_times(double duration, double dt) {
  return Eigen::VectorXd::LinSpaced(static_cast<Eigen::Index>(std::round(duration / dt)) + 1, 0.0, duration);
}

/// The URDF's values with every entry moved by up to ±20 % and friction of plausible size: the truth the
/// data are made with, different from the prior identification starts from.
inline Eigen::VectorXd perturbed_truth(const Model& model, const ParameterLayout& layout, std::mt19937_64& engine) {
  const int n = model.joint_count();
  Eigen::VectorXd pi = standard_parameters(model, layout);
  std::uniform_real_distribution<double> spread(0.8, 1.2), friction(0.2, 1.5), offset(-0.3, 0.3);
  for (Eigen::Index i = 0; i < 10 * n; ++i) pi[i] *= spread(engine);
  for (int k = 0; k < n; ++k) {
    if (layout.viscous) pi[layout.viscous_begin(n) + k] = friction(engine);
    if (layout.coulomb) pi[layout.coulomb_begin(n) + k] = 2.0 * friction(engine);
    if (layout.offset) pi[layout.offset_begin(n) + k] = offset(engine);
  }
  return pi;
}

}  // namespace manipid::robot::testing

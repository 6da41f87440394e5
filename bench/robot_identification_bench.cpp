// robot_identification_bench.cpp — the whole identification of the Panda-like 7-DOF arm from 20,000 jittery
// samples: resampling, filters, regressor, base parameters, least squares, standard errors (target ≤ 100 ms).
//
// The data: a 5-harmonic Fourier motion (period 10 s) logged at 0.7–1.3 ms steps for 20 s, torques from the
// URDF's own values with viscous and Coulomb friction and offsets; the identification runs with its
// defaults (filters chosen from the data) and friction terms viscous, Coulomb and offset.
#include "manipid/core/robot/identification.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/core/robot/urdf.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>

namespace manipid::robot {
namespace {

std::string read_example(const std::string& name) {
  const std::string path = std::string(MANIPID_SOURCE_DIR) + "/examples/robots/" + name;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

struct Run {
  Model model = parse_urdf(read_example("panda_like.urdf")).model;
  ParameterLayout layout;
  Trajectory data;

  Run() {
    layout.offset = true;
    const int n = model.joint_count();
    Eigen::VectorXd pi = standard_parameters(model, layout);
    for (int k = 0; k < n; ++k) {
      pi[layout.viscous_begin(n) + k] = 0.5;
      pi[layout.coulomb_begin(n) + k] = 1.0;
      pi[layout.offset_begin(n) + k] = 0.1;
    }
    std::mt19937_64 engine(1);
    std::uniform_real_distribution<double> amplitude(-0.15, 0.15), step(0.7e-3, 1.3e-3);
    Eigen::MatrixXd a(n, 5), b(n, 5);
    for (int k = 0; k < n; ++k) {
      for (int l = 0; l < 5; ++l) {
        a(k, l) = amplitude(engine);
        b(k, l) = amplitude(engine);
      }
    }
    const int samples = 20'000;
    data.t.resize(samples);
    data.q.resize(samples, n);
    data.tau.resize(samples, n);
    Data workspace(model);
    Eigen::VectorXd q(n), qd(n), qdd(n), tau(n);
    double t = 0.0;
    for (int s = 0; s < samples; ++s, t += step(engine)) {
      q.setZero();
      qd.setZero();
      qdd.setZero();
      for (int l = 0; l < 5; ++l) {
        const double w = 2.0 * std::numbers::pi / 10.0 * (l + 1), sine = std::sin(w * t), cosine = std::cos(w * t);
        q += (a.col(l) * sine - b.col(l) * cosine) / w;
        qd += a.col(l) * cosine + b.col(l) * sine;
        qdd += (b.col(l) * cosine - a.col(l) * sine) * w;
      }
      inverse_dynamics(model, workspace, layout, pi, q, qd, qdd, tau);
      data.t[s] = t;
      data.q.row(s) = q.transpose();
      data.tau.row(s) = tau.transpose();
    }
  }
};

const Run& run() {
  static const Run instance;
  return instance;
}

void BM_IdentifyPandaLike20000JitterySamples(benchmark::State& state) {
  const Run& r = run();
  IdentificationOptions options;
  options.layout = r.layout;
  for (auto _ : state) {
    const IdentificationResult result = identify(r.model, r.data, options);
    benchmark::DoNotOptimize(result.estimate.data());
  }
}
BENCHMARK(BM_IdentifyPandaLike20000JitterySamples)->Unit(benchmark::kMillisecond)->MinTime(2.0);

/// The same with a physically consistent estimate (the constrained fit after the least squares).
void BM_IdentifyPandaLike20000JitterySamplesPhysical(benchmark::State& state) {
  const Run& r = run();
  IdentificationOptions options;
  options.layout = r.layout;
  options.physical = true;
  for (auto _ : state) {
    const IdentificationResult result = identify(r.model, r.data, options);
    benchmark::DoNotOptimize(result.estimate.data());
  }
}
BENCHMARK(BM_IdentifyPandaLike20000JitterySamplesPhysical)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
}  // namespace manipid::robot

// dynamics_bench.cpp — cost per sample of the equations of motion for the paper's robot.
#include "manipid/core/paper/dynamics.h"
#include "manipid/core/paper/presets.h"
#include "manipid/core/paper/regressor.h"

#include <benchmark/benchmark.h>

#include <random>

namespace manipid {
namespace {

struct States {
  Eigen::MatrixXd q, qd, qdd;  // joints × samples
  explicit States(int n, int samples) : q(n, samples), qd(n, samples), qdd(n, samples) {
    std::mt19937_64 engine(3);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    for (Eigen::MatrixXd* m : {&q, &qd, &qdd})
      for (int i = 0; i < m->size(); ++i) m->data()[i] = 2.0 * uniform(engine);
  }
};

void BM_InverseDynamics(benchmark::State& state, KineticEnergy energy) {
  const Preset preset = cedro2009(energy);
  DynamicsWorkspace workspace(preset.model);
  const int samples = 1024;
  const States states(4, samples);
  Eigen::VectorXd tau(4);
  int i = 0;
  for (auto _ : state) {
    inverse_dynamics(preset.model, preset.true_parameters, workspace, states.q.col(i), states.qd.col(i),
                     states.qdd.col(i), tau);
    benchmark::DoNotOptimize(tau.data());
    i = (i + 1) % samples;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_InverseDynamics, complete, KineticEnergy::complete);
BENCHMARK_CAPTURE(BM_InverseDynamics, paper, KineticEnergy::paper);

void BM_ForwardDynamics(benchmark::State& state) {
  const Preset preset = cedro2009();
  DynamicsWorkspace workspace(preset.model);
  const States states(4, 1024);
  Eigen::VectorXd qdd(4);
  int i = 0;
  for (auto _ : state) {
    forward_dynamics(preset.model, preset.true_parameters, workspace, states.q.col(i), states.qd.col(i),
                     states.qdd.col(i), qdd);
    benchmark::DoNotOptimize(qdd.data());
    i = (i + 1) % 1024;
  }
}
BENCHMARK(BM_ForwardDynamics);

void BM_Regressor(benchmark::State& state, KineticEnergy energy) {
  const Preset preset = cedro2009(energy);
  const ParameterProducts products = parameter_products(preset.model);
  DynamicsWorkspace workspace(preset.model);
  const States states(4, 1024);
  Eigen::MatrixXd Y(4, products.size());
  int i = 0;
  for (auto _ : state) {
    regressor(preset.model, products, workspace, states.q.col(i), states.qd.col(i), states.qdd.col(i), Y);
    benchmark::DoNotOptimize(Y.data());
    i = (i + 1) % 1024;
  }
}
BENCHMARK_CAPTURE(BM_Regressor, complete, KineticEnergy::complete);
BENCHMARK_CAPTURE(BM_Regressor, paper, KineticEnergy::paper);

/// regressor_rows over 1,024 samples, four at a time (items = samples).
void BM_RegressorRows(benchmark::State& state, KineticEnergy energy) {
  const Preset preset = cedro2009(energy);
  const ParameterProducts products = parameter_products(preset.model);
  DynamicsWorkspace workspace(preset.model);
  const States states(4, 1024);
  const Eigen::MatrixXd q = states.q.transpose(), qd = states.qd.transpose(), qdd = states.qdd.transpose();
  Eigen::MatrixXd Y(4 * 1024, products.size());
  for (auto _ : state) {
    regressor_rows(preset.model, products, workspace, q, qd, qdd, Y);
    benchmark::DoNotOptimize(Y.data());
  }
  state.SetItemsProcessed(state.iterations() * 1024);
}
BENCHMARK_CAPTURE(BM_RegressorRows, complete, KineticEnergy::complete);
BENCHMARK_CAPTURE(BM_RegressorRows, paper, KineticEnergy::paper);

}  // namespace
}  // namespace manipid

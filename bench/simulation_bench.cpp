// simulation_bench.cpp — cost of the paper's closed-loop simulation (cedro2009, 9.7 s,
// Dormand–Prince 5(4) with dense output) and of its parts: the pre-filtered reference and its
// interpolation. Counters report accepted steps and right-hand-side (forward dynamics) calls;
// the tolerance sweep also reports the error against a tight-tolerance solution.
#include "manipid/core/paper/presets.h"
#include "manipid/core/paper/simulation.h"

#include <benchmark/benchmark.h>

#include <cmath>

namespace manipid {
namespace {

void report(benchmark::State& state, const SimulationSummary& summary) {
  state.counters["steps"] = benchmark::Counter(static_cast<double>(summary.steps));
  state.counters["rhs"] = benchmark::Counter(static_cast<double>(summary.rhs_evaluations));
  // Wall time of the last run per RHS call, integrator and output overhead included.
  state.counters["ns_per_rhs"] =
      benchmark::Counter(summary.wall_seconds * 1e9 / static_cast<double>(summary.rhs_evaluations));
}

void BM_Simulation_Paper(benchmark::State& state, KineticEnergy kinetic_energy) {
  const Preset preset = cedro2009(kinetic_energy);
  const SampledReference reference = make_step_reference(preset.reference);
  SimulationSummary summary;
  for (auto _ : state) {
    Trajectory trajectory = simulate_closed_loop(preset.model, preset.true_parameters, preset.controller, reference,
                                                 preset.simulation, &summary);
    benchmark::DoNotOptimize(trajectory.q.data());
  }
  report(state, summary);
}
BENCHMARK_CAPTURE(BM_Simulation_Paper, complete, KineticEnergy::complete)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Simulation_Paper, paper, KineticEnergy::paper)->Unit(benchmark::kMillisecond);

// The accuracy side of the tolerance trade-off: max |q − q_tight| and |τ − τ_tight| against
// atol 1e-14, rtol 1e-13 (computed once).
const Trajectory& tight_solution() {
  static const Trajectory solution = [] {
    const Preset preset = cedro2009();
    SimulationOptions options = preset.simulation;
    options.absolute_tolerance = 1e-14;
    options.relative_tolerance = 1e-13;
    return simulate_closed_loop(preset.model, preset.true_parameters, preset.controller,
                                make_step_reference(preset.reference), options);
  }();
  return solution;
}

// Arguments: −log10 of the absolute and the relative tolerance.
void BM_Simulation_Tolerance(benchmark::State& state) {
  const Preset preset = cedro2009();
  const SampledReference reference = make_step_reference(preset.reference);
  SimulationOptions options = preset.simulation;
  options.absolute_tolerance = std::pow(10.0, -static_cast<double>(state.range(0)));
  options.relative_tolerance = std::pow(10.0, -static_cast<double>(state.range(1)));
  const Trajectory& tight = tight_solution();
  SimulationSummary summary;
  Trajectory trajectory;
  for (auto _ : state) {
    trajectory = simulate_closed_loop(preset.model, preset.true_parameters, preset.controller, reference, options,
                                      &summary);
    benchmark::DoNotOptimize(trajectory.q.data());
  }
  report(state, summary);
  state.counters["q_error"] = (trajectory.q - tight.q).cwiseAbs().maxCoeff();
  state.counters["tau_error"] = (trajectory.tau - tight.tau).cwiseAbs().maxCoeff();
}
BENCHMARK(BM_Simulation_Tolerance)
    ->ArgNames({"atol", "rtol"})
    ->Args({10, 8})
    ->Args({9, 8})
    ->Args({8, 8})
    ->Args({6, 8})
    ->Args({10, 7})
    ->Args({10, 6})
    ->Unit(benchmark::kMillisecond);

void BM_StepReference_Paper(benchmark::State& state) {
  const StepReferenceSpec spec = cedro2009().reference;
  for (auto _ : state) {
    SampledReference reference = make_step_reference(spec);
    benchmark::DoNotOptimize(reference.values.data());
  }
}
BENCHMARK(BM_StepReference_Paper)->Unit(benchmark::kMicrosecond);

// One interpolation of all four joints, as done at every right-hand-side call.
void BM_ReferenceEvaluate(benchmark::State& state) {
  const SampledReference reference = make_step_reference(cedro2009().reference);
  Eigen::VectorXd r(reference.joint_count());
  double t = 0.0;
  for (auto _ : state) {
    reference.evaluate(t, r);
    benchmark::DoNotOptimize(r.data());
    t = t < 9.7 ? t + 0.000731 : 0.0;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ReferenceEvaluate);

}  // namespace
}  // namespace manipid

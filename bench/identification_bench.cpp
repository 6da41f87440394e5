// identification_bench.cpp — the paper's case end to end, one cost evaluation in Gram and
// direct form, and output-error / two-stage from the same start (the paper's speed claim).
#include "manipid/core/paper/identification.h"
#include "manipid/core/paper/input_error.h"
#include "manipid/core/paper/presets.h"

#include <benchmark/benchmark.h>

#include <map>
#include <random>

namespace manipid {
namespace {

const Trajectory& paper_run(bool noisy) {
  static std::map<bool, Trajectory> runs;
  auto found = runs.find(noisy);
  if (found != runs.end()) return found->second;
  const Preset preset = cedro2009();
  Trajectory data = simulate_closed_loop(preset.model, preset.true_parameters, preset.controller,
                                         make_step_reference(preset.reference), preset.simulation);
  if (noisy) {
    // The noisy paper case: σ_q = 1e-4 rad, a 16-bit encoder, τ noise 1 % of its spread.
    MeasurementNoise noise;
    noise.q_sigma = 1e-4;
    noise.quantize_bits = 16;
    noise.seed = 1;
    apply_measurement_noise(data, noise);
    std::mt19937_64 engine(2);
    for (int j = 0; j < data.joint_count(); ++j) {
      const double mean = data.tau.col(j).mean();
      const double spread = std::sqrt((data.tau.col(j).array() - mean).square().mean());
      std::normal_distribution<double> normal(0.0, 0.01 * spread);
      for (int i = 0; i < data.samples(); ++i) data.tau(i, j) += normal(engine);
    }
  }
  return runs.emplace(noisy, std::move(data)).first->second;
}

/// `algorithm` "" is the default (LM for input-error).
IdentificationOptions paper_options(const char* algorithm) {
  const Preset preset = cedro2009();
  IdentificationOptions options;
  options.initial = preset.initial_parameters;
  options.controller = preset.controller;
  options.algorithm = algorithm;
  options.half_length = 100;
  options.band = 0.2;
  return options;
}

// Filter + regressor + optimisation + uncertainty, 8 free parameters, the paper's filter.
void BM_InputError_PaperCase(benchmark::State& state, const char* algorithm) {
  const Preset preset = cedro2009();
  const Trajectory& data = paper_run(false);
  const IdentificationOptions options = paper_options(algorithm);
  long evaluations = 0;
  for (auto _ : state) {
    const IdentificationResult result = identify(preset.model, data, options);
    evaluations = result.evaluations;
    benchmark::DoNotOptimize(result.estimate.data());
  }
  state.counters["evaluations"] = static_cast<double>(evaluations);
}
BENCHMARK_CAPTURE(BM_InputError_PaperCase, default_LM, "")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_InputError_PaperCase, LN_BOBYQA, "LN_BOBYQA")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_InputError_PaperCase, LD_SLSQP, "LD_SLSQP")->Unit(benchmark::kMillisecond);

// The same with the filter chosen from the data: the default request (LM), and with LN_BOBYQA.
void BM_InputError_AutoFilter(benchmark::State& state, const char* algorithm) {
  const Preset preset = cedro2009();
  IdentificationOptions options = paper_options(algorithm);
  options.half_length = 0;
  options.band = 0.0;
  long evaluations = 0;
  for (auto _ : state) {
    const IdentificationResult result = identify(preset.model, paper_run(false), options);
    evaluations = result.evaluations;
    benchmark::DoNotOptimize(result.estimate.data());
  }
  state.counters["evaluations"] = static_cast<double>(evaluations);
}
BENCHMARK_CAPTURE(BM_InputError_AutoFilter, default_LM, "")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_InputError_AutoFilter, LN_BOBYQA, "LN_BOBYQA")->Unit(benchmark::kMillisecond);

void BM_Cost(benchmark::State& state, bool gram) {
  const Preset preset = cedro2009();
  const FilteredData data = filter_for_input_error(paper_run(false), {100, 0.2, 0.001}, false, std::nullopt);
  const InputErrorCost cost(preset.model, data);
  for (auto _ : state) {
    benchmark::DoNotOptimize(gram ? cost.evaluate(preset.initial_parameters) : cost.evaluate_direct(preset.initial_parameters));
  }
}
BENCHMARK_CAPTURE(BM_Cost, gram, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Cost, direct, false)->Unit(benchmark::kMicrosecond);

void BM_Simulating(benchmark::State& state, IdentificationMethod method, bool noisy) {
  const Preset preset = cedro2009();
  IdentificationOptions options = paper_options("LN_BOBYQA");
  options.method = method;
  options.half_length = 0;  // two-stage starts from the automatic filter
  options.band = 0.0;
  long simulations = 0, evaluations = 0;
  for (auto _ : state) {
    const IdentificationResult result = identify(preset.model, paper_run(noisy), options);
    simulations = result.simulations;
    evaluations = result.evaluations;
  }
  state.counters["simulations"] = static_cast<double>(simulations);
  state.counters["evaluations"] = static_cast<double>(evaluations);
}
BENCHMARK_CAPTURE(BM_Simulating, output_error, IdentificationMethod::output_error, false)
    ->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Simulating, two_stage_noisy, IdentificationMethod::two_stage, true)
    ->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace manipid

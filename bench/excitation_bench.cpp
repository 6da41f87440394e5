// excitation_bench.cpp — optimal excitation design (robot/excitation.h) at default settings: the Panda-like
// 7-DOF arm (the product's target: ≤ 30 s, Release, one core, 5 harmonics) and the UR5-like 6-DOF arm.
//
// One design per iteration (seconds each), so one iteration per run; the counters give what the design
// reached: the condition number of the column-scaled base regressor at the best random start and at the
// end, the evaluations, and the time per evaluation.
#include "manipid/core/robot/excitation.h"
#include "manipid/core/robot/urdf.h"

#include <benchmark/benchmark.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace manipid::robot {
namespace {

Model example_robot(const std::string& file) {
  const std::string path = std::string(MANIPID_SOURCE_DIR) + "/examples/robots/" + file;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::stringstream text;
  text << in.rdbuf();
  return parse_urdf(text.str()).model;
}

void BM_ExcitationDesign(benchmark::State& state, const std::string& file, ExcitationCriterion criterion) {
  const Model model = example_robot(file);
  ExcitationOptions options;  // defaults: period 10 s, 5 harmonics, 4000 evaluations, seed 1
  options.criterion = criterion;
  ExcitationSummary summary;
  for (auto _ : state) {
    const ExcitationDesign design = design_excitation(model, options);
    summary = design.summary;
    benchmark::DoNotOptimize(design.trajectory.a.data());
  }
  state.counters["cond_start"] = summary.initial_condition_number;
  state.counters["cond"] = summary.condition_number;
  state.counters["log_det"] = summary.log_det;
  state.counters["evaluations"] = static_cast<double>(summary.evaluations);
  state.counters["ms_per_evaluation"] = 1e3 * summary.wall_seconds / static_cast<double>(summary.evaluations);
  state.SetLabel(std::string(to_string(summary.termination)) + ", " + std::to_string(summary.base_parameters) +
                 " base parameters");
}
BENCHMARK_CAPTURE(BM_ExcitationDesign, panda_condition, "panda_like.urdf", ExcitationCriterion::condition)
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_ExcitationDesign, panda_logdet, "panda_like.urdf", ExcitationCriterion::logdet)
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_ExcitationDesign, ur5_condition, "ur5_like.urdf", ExcitationCriterion::condition)
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

}  // namespace
}  // namespace manipid::robot

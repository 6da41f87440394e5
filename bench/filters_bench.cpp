// filters_bench.cpp — cost of the paper's differential filters (filters.h) at the paper's
// scale: 4 joints × 9,701 samples (10 s at 1 kHz minus the 0.3 s the paper trims), M = 100,
// and longer filters (the FFT path). Target: apply_all over the four joints ≤ 5 ms on one core.
#include "manipid/core/signal/filters.h"

#include <benchmark/benchmark.h>

#include <cmath>

namespace {

using manipid::DifferentialFilter;
using manipid::FilterOrder;
using manipid::FilterSettings;

constexpr int joints = 4;
constexpr int samples = 9701;

FilterSettings paper_settings(int half_length = 100) {
  FilterSettings settings;
  settings.half_length = half_length;
  settings.band = 0.2;
  settings.dt = 0.001;
  return settings;
}

// Smooth joint-like trajectories, one column per joint.
Eigen::MatrixXd joint_signals() {
  Eigen::MatrixXd q(samples, joints);
  for (int k = 0; k < joints; ++k) {
    for (int i = 0; i < samples; ++i) {
      const double t = 0.001 * i;
      q(i, k) = 0.5 * std::tanh(4.0 * (t - 1.0 - 2.0 * k)) + 0.01 * std::sin((3.0 + k) * t);
    }
  }
  return q;
}

// The identification's case: value, velocity and acceleration of every joint.
void BM_Filters_AllThree_4x9701(benchmark::State& state) {
  const DifferentialFilter filter(paper_settings(static_cast<int>(state.range(0))));
  const Eigen::MatrixXd q = joint_signals();
  const int outputs = filter.output_length(samples);
  Eigen::MatrixXd value(outputs, joints), velocity(outputs, joints), acceleration(outputs, joints);
  for (auto _ : state) {
    for (int k = 0; k < joints; ++k) filter.apply_all(q.col(k), value.col(k), velocity.col(k), acceleration.col(k));
    benchmark::DoNotOptimize(value.data());
    benchmark::DoNotOptimize(velocity.data());
    benchmark::DoNotOptimize(acceleration.data());
    benchmark::ClobberMemory();
  }
  // Items = output samples of all three filters.
  state.SetItemsProcessed(state.iterations() * 3LL * joints * outputs);
}
// Arg: M. The direct sum up to M = 191, the FFT from M = 192 (DifferentialFilter::
// fft_min_half_length): the paper's M, both sides of the switch, and the automatic choice's
// longest M.
BENCHMARK(BM_Filters_AllThree_4x9701)->Arg(100)->Arg(191)->Arg(192)->Arg(400)->Arg(1000)->Unit(benchmark::kMillisecond);

// One order at a time over the same data (arg: 0 lowpass, 1 derivative1, 2 derivative2).
void BM_Filters_Single_4x9701_M100(benchmark::State& state) {
  const auto order = static_cast<FilterOrder>(state.range(0));
  const DifferentialFilter filter(paper_settings());
  const Eigen::MatrixXd q = joint_signals();
  Eigen::MatrixXd out(filter.output_length(samples), joints);
  for (auto _ : state) {
    for (int k = 0; k < joints; ++k) filter.apply(order, q.col(k), out.col(k));
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * joints * out.rows());
}
BENCHMARK(BM_Filters_Single_4x9701_M100)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// Building the three coefficient sets (what cached_filter saves), by half-length M.
void BM_Filters_Construct(benchmark::State& state) {
  const FilterSettings settings = paper_settings(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    DifferentialFilter filter(settings);
    benchmark::DoNotOptimize(filter.coefficients(FilterOrder::derivative2).data());
  }
}
BENCHMARK(BM_Filters_Construct)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);

// A cache hit: lock, map lookup, shared_ptr copy.
void BM_Filters_CachedLookup(benchmark::State& state) {
  const FilterSettings settings = paper_settings();
  manipid::cached_filter(settings);
  for (auto _ : state) benchmark::DoNotOptimize(manipid::cached_filter(settings));
}
BENCHMARK(BM_Filters_CachedLookup);

}  // namespace

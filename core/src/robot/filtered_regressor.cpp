// filtered_regressor.cpp — D's states on the working grid, the regressor there, and L over its columns and
// the torque alike (robot/filtered_regressor.h).
#include "manipid/core/robot/filtered_regressor.h"

#include "manipid/core/errors.h"
#include "numbers.h"
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/regressor.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/core/signal/butterworth.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace manipid::robot {
namespace {

constexpr int kLowpassOrder = 4;

/// The standard indices of row k's non-zero columns: bodies k..n−1, then joint k's friction and armature.
std::vector<int> row_columns(const ParameterLayout& layout, int n, int k) {
  std::vector<int> columns;
  for (int c = kInertialParametersPerBody * k; c < kInertialParametersPerBody * n; ++c) columns.push_back(c);
  for (int begin : {layout.viscous_begin(n), layout.coulomb_begin(n), layout.offset_begin(n), layout.armature_begin(n)}) {
    if (begin >= 0) columns.push_back(begin + k);
  }
  return columns;
}

/// Σ h² of filtfilt's impulse response at `cutoff_hz` on a grid `dt` apart.
double lowpass_energy(const IirFilter& filter, double cutoff_hz, double dt) {
  const int half = static_cast<int>(std::ceil(20.0 / (cutoff_hz * dt))) + filtfilt_padding(filter);
  Eigen::VectorXd impulse = Eigen::VectorXd::Zero(2 * half + 1);
  impulse[half] = 1.0;
  filtfilt(filter, impulse, impulse);
  return impulse.squaredNorm();
}

}  // namespace

int FilterPair::shortest_data() const {
  const int trim = static_cast<int>(std::ceil(trim_seconds / differentiation.dt));
  return 2 * differentiation.half_length + 1 + 2 * trim + 8 * working_step;
}

std::vector<double> candidate_cutoffs(double given_hz, double judge_cutoff_hz, double dt) {
  if (given_hz > 0) return {given_hz};
  std::vector<double> cutoffs;
  for (double factor : kCutoffFactors) {
    const double cutoff = factor * judge_cutoff_hz;
    if (cutoff < 0.1 / dt) cutoffs.push_back(cutoff);  // at most a fifth of the Nyquist frequency
  }
  if (cutoffs.empty()) cutoffs.push_back(std::min(judge_cutoff_hz, 0.1 / dt));
  return cutoffs;
}

double held_out_guard(double cutoff_hz, double judge_cutoff_hz, const FilterPair& filters) {
  return 0.5 / cutoff_hz + 0.5 / judge_cutoff_hz + filters.differentiation.half_length * filters.differentiation.dt;
}

FilterPair differentiation_for(double highest_cutoff_hz, double dt, double trim_seconds) {
  FilterPair filters;
  filters.trim_seconds = trim_seconds;
  filters.comparison_cutoff_hz = highest_cutoff_hz;
  const double band = std::min(std::numbers::pi / 2.0, 2.0 * std::numbers::pi * 3.0 * highest_cutoff_hz * dt);
  filters.differentiation = FilterSettings{std::max(2, static_cast<int>(std::ceil(6.4 * std::numbers::pi / band))), band, dt};
  filters.working_step = working_step(filters.differentiation);
  return filters;
}

int working_step(const FilterSettings& differentiation) {
  // f_g Δ = Ωg / 2π: k = ⌊1 / (4 f_g Δ)⌋ = ⌊π / (2 Ωg)⌋.
  return std::max(1, static_cast<int>(std::floor(std::numbers::pi / (2.0 * differentiation.band))));
}

RegressorSignals regressor_signals(const Model& model, const ParameterLayout& layout, const Trajectory& data,
                                   const FilterPair& filters, const std::atomic<bool>* cancel) {
  filters.differentiation.validate();
  const int n = model.joint_count();
  if (data.joint_count() != n) {
    throw InputError("q", "the data has " + std::to_string(data.joint_count()) + " joints, the robot " + std::to_string(n));
  }
  if (data.samples() < filters.shortest_data()) {
    throw InputError("samples", "the filters (differentiation half-length M = " +
                                    std::to_string(filters.differentiation.half_length) + ", " +
                                    manipid::detail::message_number(filters.trim_seconds) + " s trimmed at each end) need at least " +
                                    std::to_string(filters.shortest_data()) + " samples; the data has " +
                                    std::to_string(data.samples()) + " (" +
                                    manipid::detail::message_number(data.t[data.samples() - 1] - data.t[0]) + " s)");
  }
  const auto differentiation = cached_filter(filters.differentiation);
  const int M = filters.differentiation.half_length;
  const int k = filters.working_step;
  const int N1 = differentiation->output_length(data.samples());
  const int samples = (N1 - 1) / k + 1;

  Eigen::MatrixXd q(n, samples), qd(n, samples), qdd(n, samples);
  // sign(q̇) at every sample of D's output: Coulomb friction's column is a step at each reversal, which the
  // working grid could place only to within k samples; it is formed here, anti-aliased like τ and sampled.
  Eigen::MatrixXd coulomb(layout.coulomb && k > 1 ? N1 : 0, n);
  {
    Eigen::VectorXd f0(N1), f1(N1), f2(N1);
    for (int j = 0; j < n; ++j) {
      differentiation->apply_all(data.q.col(j), f0, f1, f2);
      for (int s = 0; s < samples; ++s) {
        q(j, s) = f0[s * k];
        qd(j, s) = f1[s * k];
        qdd(j, s) = f2[s * k];
      }
      if (coulomb.rows()) {
        for (int s = 0; s < N1; ++s) coulomb(s, j) = friction_sign(f1[s]);
      }
    }
  }
  RegressorSignals signals;
  signals.dt = filters.working_dt();
  signals.t.resize(samples);
  for (int s = 0; s < samples; ++s) signals.t[s] = data.t[M + s * k];
  // Anti-aliasing at a quarter of the working rate before the working grid samples the torque and the
  // Coulomb columns.
  const IirFilter anti_aliasing = butterworth_lowpass(kLowpassOrder, 0.25 / signals.dt, data.dt());
  if (data.has_torque()) {
    const Eigen::MatrixXd tau = k > 1 ? filtfilt_columns(anti_aliasing, data.tau) : data.tau;
    signals.tau.resize(samples, n);
    for (int s = 0; s < samples; ++s) signals.tau.row(s) = tau.row(M + s * k);
  }
  if (coulomb.rows()) coulomb = filtfilt_columns(anti_aliasing, coulomb);
  signals.columns.resize(static_cast<std::size_t>(n));
  signals.Y.resize(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    signals.columns[static_cast<std::size_t>(j)] = row_columns(layout, n, j);
    signals.Y[static_cast<std::size_t>(j)].resize(samples, static_cast<Eigen::Index>(signals.columns[static_cast<std::size_t>(j)].size()));
  }
  Data workspace(model);
  Eigen::MatrixXd Y(n, layout.size(n));
  const int coulomb_begin = layout.coulomb_begin(n);
  for (int s = 0; s < samples; ++s) {
    if (cancel && (s & 1023) == 0 && cancel->load(std::memory_order_relaxed)) return RegressorSignals{};
    regressor(model, workspace, layout, q.col(s), qd.col(s), qdd.col(s), Y);
    if (coulomb.rows()) {
      for (int j = 0; j < n; ++j) Y(j, coulomb_begin + j) = coulomb(s * k, j);
    }
    for (int j = 0; j < n; ++j) {
      const auto& columns = signals.columns[static_cast<std::size_t>(j)];
      auto& target = signals.Y[static_cast<std::size_t>(j)];
      for (std::size_t c = 0; c < columns.size(); ++c) target(s, static_cast<Eigen::Index>(c)) = Y(j, columns[c]);
    }
  }
  return signals;
}

FilteredRows filtered_rows(const RegressorSignals& signals, int parameter_count, double cutoff_hz, double trim_seconds,
                           const std::vector<int>& joints, const std::vector<int>& wanted) {
  const double nyquist = 0.5 / signals.dt;
  if (!(cutoff_hz > 0.0 && cutoff_hz < nyquist)) {
    throw InputError("comparison_cutoff", "the comparison low-pass's cut-off must lie between 0 and " + manipid::detail::message_number(nyquist) +
                                              " Hz (the working grid's Nyquist frequency), not " + manipid::detail::message_number(cutoff_hz) + " Hz");
  }
  const IirFilter lowpass = butterworth_lowpass(kLowpassOrder, cutoff_hz, signals.dt);
  FilteredRows rows;
  rows.joints = joints;
  rows.row_step = std::max(1, static_cast<int>(std::floor(1.0 / (5.0 * cutoff_hz * signals.dt))));
  rows.lowpass_energy = lowpass_energy(lowpass, cutoff_hz, signals.dt);
  const Eigen::Index N = signals.t.size();
  Eigen::Index first = 0, last = N - 1;
  while (first < N && signals.t[first] < signals.t[0] + trim_seconds) ++first;
  while (last >= 0 && signals.t[last] > signals.t[N - 1] - trim_seconds) --last;
  if (last < first) {
    throw InputError("samples", "nothing is left of the data after trimming " + manipid::detail::message_number(trim_seconds) + " s at each end");
  }
  const Eigen::Index R = (last - first) / rows.row_step + 1;
  const Eigen::Index J = static_cast<Eigen::Index>(joints.size());
  // Where each standard parameter lands in W (−1: not asked for).
  std::vector<Eigen::Index> position(static_cast<std::size_t>(parameter_count), -1);
  Eigen::Index width = 0;
  if (wanted.empty()) {
    for (int c = 0; c < parameter_count; ++c) position[static_cast<std::size_t>(c)] = width++;
  } else {
    for (int c : wanted) position[static_cast<std::size_t>(c)] = width++;
  }
  rows.t.resize(R);
  for (Eigen::Index r = 0; r < R; ++r) rows.t[r] = signals.t[first + r * rows.row_step];
  rows.W = Eigen::MatrixXd::Zero(R * J, width);
  rows.tau = signals.tau.size() ? Eigen::VectorXd(R * J) : Eigen::VectorXd();
  const Eigen::MatrixXd tau = signals.tau.size() ? filtfilt_columns(lowpass, signals.tau) : Eigen::MatrixXd();
  for (Eigen::Index jj = 0; jj < J; ++jj) {
    const auto j = static_cast<std::size_t>(joints[static_cast<std::size_t>(jj)]);
    std::vector<Eigen::Index> from, to;
    for (std::size_t c = 0; c < signals.columns[j].size(); ++c) {
      const Eigen::Index at = position[static_cast<std::size_t>(signals.columns[j][c])];
      if (at >= 0) {
        from.push_back(static_cast<Eigen::Index>(c));
        to.push_back(at);
      }
    }
    const Eigen::MatrixXd filtered = filtfilt_columns(lowpass, signals.Y[j](Eigen::all, from));
    for (Eigen::Index r = 0; r < R; ++r) {
      const Eigen::Index s = first + r * rows.row_step;
      for (std::size_t c = 0; c < to.size(); ++c) rows.W(r * J + jj, to[c]) = filtered(s, static_cast<Eigen::Index>(c));
      if (tau.size()) rows.tau[r * J + jj] = tau(s, static_cast<Eigen::Index>(j));
    }
  }
  return rows;
}

}  // namespace manipid::robot

// resample.cpp — stale repeats, uniform grids and trimming for logged data (resample.h).
#include "manipid/core/signal/resample.h"

#include "manipid/core/errors.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace manipid {
namespace {

/// A logger that misses a sample logs the previous one again under the new time stamp, once or a few
/// times in a row (the Panda's log: runs of 1–2); more identical rows than this are a robot at rest.
constexpr Eigen::Index kLongestStaleRun = 3;

/// The measured blocks of a trajectory, in one list, so every step treats them alike.
std::vector<const Eigen::MatrixXd*> blocks(const Trajectory& data) {
  return {&data.q, &data.tau, &data.ref, &data.qd, &data.qdd};
}
std::vector<Eigen::MatrixXd*> blocks(Trajectory& data) { return {&data.q, &data.tau, &data.ref, &data.qd, &data.qdd}; }

bool same_row(const Trajectory& data, Eigen::Index a, Eigen::Index b) {
  for (const Eigen::MatrixXd* block : blocks(data)) {
    if (block->cols() > 0 && block->row(a) != block->row(b)) return false;
  }
  return true;
}

std::string seconds(double value) {
  std::ostringstream text;
  text.precision(6);
  text << value << " s";
  return text.str();
}

std::string milliseconds(double value) {
  std::ostringstream text;
  text.precision(3);
  text << value * 1e3;
  return text.str();
}

/// Piecewise-cubic Hermite interpolation of the columns of `values` (rows at times `t`) at the
/// uniform times t0 + k·dt. Slopes at the knots are the derivative of the parabola through the
/// knot and its neighbours (exact for quadratics on any spacing); one-sided at the ends.
Eigen::MatrixXd interpolate(const Eigen::VectorXd& t, const Eigen::MatrixXd& values, double t0, double dt, Eigen::Index count) {
  const Eigen::Index n = t.size();
  Eigen::MatrixXd slopes(n, values.cols());
  if (n == 2) slopes.rowwise() = (values.row(1) - values.row(0)) / (t[1] - t[0]);  // one segment: a line
  for (Eigen::Index i = 0; i < n && n > 2; ++i) {
    // Three-point derivative at knot i from knots a < b < c with i one of them.
    const Eigen::Index b = std::clamp<Eigen::Index>(i, 1, n - 2);
    const Eigen::Index a = b - 1, c = b + 1;
    const double ha = t[b] - t[a], hc = t[c] - t[b];
    const double x = t[i] - t[b];  // where on the parabola: -ha, 0 or +hc
    // d/dx of the Lagrange parabola through (−ha, ya), (0, yb), (hc, yc):
    const double wa = (2 * x - hc) / (ha * (ha + hc));
    const double wb = -(2 * x + ha - hc) / (ha * hc);
    const double wc = (2 * x + ha) / (hc * (ha + hc));
    slopes.row(i) = wa * values.row(a) + wb * values.row(b) + wc * values.row(c);
  }
  Eigen::MatrixXd out(count, values.cols());
  Eigen::Index segment = 0;
  for (Eigen::Index k = 0; k < count; ++k) {
    const double time = std::min(t0 + static_cast<double>(k) * dt, t[n - 1]);
    while (segment + 2 < n && t[segment + 1] <= time) ++segment;
    const double h = t[segment + 1] - t[segment];
    const double s = (time - t[segment]) / h;
    const double s2 = s * s, s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    out.row(k) = h00 * values.row(segment) + h10 * h * slopes.row(segment) + h01 * values.row(segment + 1) +
                 h11 * h * slopes.row(segment + 1);
  }
  return out;
}

}  // namespace

std::string TimingReport::warning() const {
  if (!resampled) return "";
  std::ostringstream text;
  if (repeats_dropped == 0 && max_step - min_step <= 1e-6 * median_step) {
    // Uniform data asked onto another period (a second run onto the identification's grid).
    text.precision(6);
    text << "resampled from its uniform " << median_step * 1e3 << " ms steps onto a " << dt * 1e3
         << " ms grid by cubic interpolation, " << samples_out << " samples";
    return text.str();
  }
  text << "time steps are not uniform (" << milliseconds(min_step) << " to " << milliseconds(max_step)
       << " ms around a median of " << milliseconds(median_step) << " ms";
  if (repeats_dropped > 0) text << "; " << repeats_dropped << " repeated rows dropped";
  text << "): resampled onto a uniform " << milliseconds(dt) << " ms grid by cubic interpolation, " << samples_out
       << " samples";
  return text.str();
}

namespace {

// Validates `data` and `options` as make_uniform does; true when make_uniform returns the data
// unchanged: already uniform, on the period asked for (or any, dt = 0).
bool uniform_as_is(const Trajectory& data, const UniformOptions& options) {
  data.validate();
  if (!(options.dt == 0.0 || (options.dt >= kShortestSamplePeriod && options.dt <= kLongestSamplePeriod))) {
    std::ostringstream text;
    text << "dt must be 0 (the median step) or a period from " << kShortestSamplePeriod << " to " << kLongestSamplePeriod
         << " s, got " << options.dt;
    throw InputError("dt", text.str());
  }
  if (!(options.max_gap_steps >= 1.0)) throw InputError("max_gap_steps", "max_gap_steps must be at least 1");
  const double first_step = data.t[1] - data.t[0];
  return data.is_uniform() && (options.dt == 0.0 || std::abs(options.dt - first_step) <= 1e-6 * first_step);
}

}  // namespace

Trajectory make_uniform(const Trajectory& data, const UniformOptions& options, TimingReport* report) {
  TimingReport found;
  found.samples_in = data.samples();
  if (uniform_as_is(data, options)) {
    const double first_step = data.t[1] - data.t[0];
    found.min_step = found.median_step = found.max_step = found.dt = first_step;
    found.samples_out = data.samples();
    if (report) *report = found;
    return data;
  }

  // 1. Stale repeats: a row equal in every measured value to the one before it, in a run of at most
  //    kLongestStaleRun such rows. A longer run is the robot at rest, measured: kept.
  std::vector<Eigen::Index> kept;
  found.min_step = data.t[1] - data.t[0];
  for (Eigen::Index i = 1; i < data.t.size(); ++i) found.min_step = std::min(found.min_step, data.t[i] - data.t[i - 1]);
  for (Eigen::Index i = 0; i < data.t.size();) {
    Eigen::Index end = i + 1;  // rows i+1 .. end-1 repeat row i
    while (end < data.t.size() && same_row(data, end, i)) ++end;
    const Eigen::Index repeats = end - i - 1;
    if (repeats <= kLongestStaleRun) {
      kept.push_back(i);
      found.repeats_dropped += static_cast<int>(repeats);
    } else {
      for (Eigen::Index k = i; k < end; ++k) kept.push_back(k);
    }
    i = end;
  }
  if (kept.size() < 2) throw InputError("t", "every row repeats the first: the data hold a single measurement");
  Trajectory distinct;
  distinct.t.resize(static_cast<Eigen::Index>(kept.size()));
  for (std::size_t k = 0; k < kept.size(); ++k) distinct.t[static_cast<Eigen::Index>(k)] = data.t[kept[k]];
  const auto source = blocks(data);
  const auto target = blocks(distinct);
  for (std::size_t b = 0; b < source.size(); ++b) {
    if (source[b]->cols() == 0) continue;  // an absent block stays absent
    target[b]->resize(static_cast<Eigen::Index>(kept.size()), source[b]->cols());
    for (std::size_t k = 0; k < kept.size(); ++k) target[b]->row(static_cast<Eigen::Index>(k)) = source[b]->row(kept[k]);
  }

  found.median_step = distinct.median_step();
  found.dt = options.dt > 0.0 ? options.dt : found.median_step;
  if (!(found.dt >= kShortestSamplePeriod && found.dt <= kLongestSamplePeriod)) {
    throw InputError("t", "the median step of t without repeated rows is " + seconds(found.dt) +
                              ", outside the periods manipid works with" + time_unit_hint(found.dt));
  }

  // 2. Gaps no interpolation can fill.
  found.max_step = 0.0;
  const double longest = options.max_gap_steps * found.dt;
  for (Eigen::Index i = 1; i < distinct.t.size(); ++i) {
    const double step = distinct.t[i] - distinct.t[i - 1];
    found.max_step = std::max(found.max_step, step);
    if (step > longest) {
      const auto first = kept[static_cast<std::size_t>(i - 1)], second = kept[static_cast<std::size_t>(i)];
      std::ostringstream text;
      text.precision(6);
      text << "a gap of " << step << " s (" << step / found.dt << " sample periods) between t = " << distinct.t[i - 1]
           << " s (sample " << first + 1 << ") and t = " << distinct.t[i] << " s (sample " << second + 1
           << "), longer than the " << longest
           << " s interpolation may bridge; trim it away (--trim) or identify the parts separately";
      throw InputError("t", text.str());
    }
  }

  // 3. The uniform grid t0, t0 + Δ, ... up to the last time stamp.
  const double t0 = distinct.t[0];
  const double span = distinct.t[distinct.t.size() - 1] - t0;
  const auto count = static_cast<Eigen::Index>(std::floor(span / found.dt * (1.0 + 1e-12))) + 1;
  Trajectory uniform;
  uniform.t = Eigen::VectorXd::LinSpaced(count, t0, t0 + static_cast<double>(count - 1) * found.dt);
  const auto resampled_target = blocks(uniform);
  const auto distinct_source = blocks(static_cast<const Trajectory&>(distinct));
  for (std::size_t b = 0; b < distinct_source.size(); ++b) {
    if (distinct_source[b]->cols() == 0) continue;
    *resampled_target[b] = interpolate(distinct.t, *distinct_source[b], t0, found.dt, count);
  }
  found.resampled = true;
  found.samples_out = static_cast<int>(count);
  uniform.validate();
  if (report) *report = found;
  return uniform;
}

Trajectory trim(const Trajectory& data, double start, double end) {
  if (!std::isfinite(start) || !std::isfinite(end) || start < 0.0 || end < 0.0) {
    throw InputError("trim", "trim needs two non-negative numbers of seconds (start, end)");
  }
  if (data.samples() == 0) return data;
  // Times printed with limited digits: a sample within 1e-6 of a step of the edge is on it.
  const double slack = 1e-6 * data.sample_period();
  const double from = data.t[0] + start - slack;
  const double to = data.t[data.t.size() - 1] - end + slack;
  Eigen::Index first = 0, last = data.t.size() - 1;
  while (first < data.t.size() && data.t[first] < from) ++first;
  while (last >= 0 && data.t[last] > to) --last;
  if (last - first + 1 < 2) {
    std::ostringstream text;
    text << "trimming " << start << " s at the start and " << end << " s at the end leaves fewer than 2 samples of the "
         << data.t[data.t.size() - 1] - data.t[0] << " s run";
    throw InputError("trim", text.str());
  }
  Trajectory trimmed;
  const Eigen::Index count = last - first + 1;
  trimmed.t = data.t.segment(first, count);
  const auto source = blocks(data);
  const auto target = blocks(trimmed);
  for (std::size_t b = 0; b < source.size(); ++b) {
    if (source[b]->cols() > 0) *target[b] = source[b]->middleRows(first, count);
  }
  return trimmed;
}

Trajectory prepare_data(const Trajectory& data, const DataPreparation& options, std::vector<std::string>* warnings) {
  std::optional<Trajectory> storage;
  const Trajectory& prepared = prepare_data(data, options, storage, warnings);
  if (storage) return std::move(*storage);
  return prepared;
}

const Trajectory& prepare_data(const Trajectory& data, const DataPreparation& options, std::optional<Trajectory>& storage,
                               std::vector<std::string>* warnings) {
  const bool trimming = options.trim_start > 0.0 || options.trim_end > 0.0;
  if (!trimming && uniform_as_is(data, options.uniform)) return data;
  if (trimming) {
    data.validate();
    storage = trim(data, options.trim_start, options.trim_end);
    if (uniform_as_is(*storage, options.uniform)) return *storage;
  }
  TimingReport report;
  Trajectory uniform = make_uniform(storage ? *storage : data, options.uniform, &report);
  if (warnings && report.resampled) warnings->push_back(report.warning());
  storage = std::move(uniform);
  return *storage;
}

PreparedRuns prepare_runs(const std::vector<Trajectory>& runs, const DataPreparation& options,
                          std::vector<std::optional<Trajectory>>& storage, std::vector<std::string>& warnings) {
  PreparedRuns prepared;
  storage.resize(runs.size());
  DataPreparation same = options;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    std::vector<std::string> run_warnings;
    prepared.push_back(std::cref(prepare_data(runs[i], same, storage[i], &run_warnings)));
    if (i == 0) same.uniform.dt = prepared.front().get().dt();
    for (std::string& warning : run_warnings) {
      warnings.push_back(runs.size() > 1 ? "run " + std::to_string(i + 1) + ": " + warning : warning);
    }
  }
  return prepared;
}

}  // namespace manipid

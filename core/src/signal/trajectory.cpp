// trajectory.cpp — consistency checks of sampled joint data (Trajectory::validate), so that
// every algorithm downstream can assume matching sizes, finite values and increasing time.
#include "manipid/core/signal/trajectory.h"

#include "manipid/core/errors.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>
#include <string>

namespace manipid {
namespace {

// Samples are numbered from 1 in messages, like the joints ("q2 is NaN at sample 1" is
// the first row), which is what a user counting rows of a table expects.
std::string describe_sample(const Eigen::VectorXd& t, Eigen::Index index) {
  std::ostringstream text;
  text << "sample " << index + 1;
  if (index < t.size() && std::isfinite(t[index])) text << " (t = " << t[index] << " s)";
  return text.str();
}

void check_columns(const std::string& field, const Eigen::MatrixXd& values, int samples,
                   int joints, bool optional) {
  if (optional && values.cols() == 0) return;
  if (values.cols() != joints) {
    std::ostringstream text;
    text << field << " has " << values.cols() << " columns but q has " << joints << " joints"
         << (optional ? " (give all of them or none)" : "");
    throw InputError(field, text.str());
  }
  if (values.rows() != samples) {
    std::ostringstream text;
    text << field << " has " << values.rows() << " samples but t has " << samples;
    throw InputError(field, text.str());
  }
}

void check_finite(const std::string& field, const Eigen::MatrixXd& values, const Eigen::VectorXd& t) {
  // x·0 is 0 for every finite x and NaN for any other, and Eigen's sum is vectorised (allFinite
  // is not, a comparison at a time): the loop below only runs to name the first culprit.
  if ((values.array() * 0.0).sum() == 0.0) return;
  // Column-major storage: scan each joint's contiguous signal.
  for (Eigen::Index column = 0; column < values.cols(); ++column) {
    for (Eigen::Index row = 0; row < values.rows(); ++row) {
      const double value = values(row, column);
      if (std::isfinite(value)) continue;
      std::ostringstream text;
      text << field << column + 1 << " is " << (std::isnan(value) ? "NaN" : "infinite") << " at "
           << describe_sample(t, row);
      throw InputError(field, text.str());
    }
  }
}

}  // namespace

double Trajectory::median_step() const {
  if (samples() < 2) return 0.0;
  Eigen::VectorXd steps = t.tail(t.size() - 1) - t.head(t.size() - 1);
  auto middle = steps.data() + steps.size() / 2;
  std::nth_element(steps.data(), middle, steps.data() + steps.size());
  return *middle;
}

bool Trajectory::is_uniform() const {
  if (samples() < 2) return true;
  const double period = t[1] - t[0];
  for (Eigen::Index i = 1; i < t.size(); ++i) {
    if (std::abs((t[i] - t[i - 1]) - period) > 1e-6 * period) return false;
  }
  return true;
}

void Trajectory::validate() const {
  if (q.cols() < 1) throw InputError("q", "q has no joint columns");
  if (t.size() < 2) {
    throw InputError("t", "a trajectory needs at least 2 samples, got " + std::to_string(t.size()));
  }
  const int sample_count = samples();
  const int joints = joint_count();
  check_columns("q", q, sample_count, joints, false);
  check_columns("tau", tau, sample_count, joints, true);
  check_columns("ref", ref, sample_count, joints, true);
  check_columns("qd", qd, sample_count, joints, true);
  check_columns("qdd", qdd, sample_count, joints, true);

  for (Eigen::Index i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t[i])) {
      throw InputError("t", std::string("t is ") + (std::isnan(t[i]) ? "NaN" : "infinite") + " at " +
                                describe_sample(t, i));
    }
  }
  for (Eigen::Index i = 1; i < t.size(); ++i) {
    if (!(t[i] > t[i - 1])) {
      throw InputError("t", "t is not strictly increasing at " + describe_sample(t, i) +
                                " (previous t = " + std::to_string(t[i - 1]) + " s)");
    }
  }
  const double period = sample_period();
  if (!(period >= kShortestSamplePeriod && period <= kLongestSamplePeriod)) {
    std::ostringstream text;
    text << "the sample period (the median step of t) is " << period << " s, outside the range manipid works with, "
         << kShortestSamplePeriod << " to " << kLongestSamplePeriod << " s" << time_unit_hint(period);
    throw InputError("t", text.str());
  }
  check_finite("q", q, t);
  check_finite("tau", tau, t);
  check_finite("ref", ref, t);
  check_finite("qd", qd, t);
  check_finite("qdd", qdd, t);
}

std::string time_unit_hint(double median_step) {
  if (!(median_step > kLongestSamplePeriod) || !std::isfinite(median_step)) return {};
  for (const auto& [scale, unit, name] : {std::tuple{1e9, "ns", "nanoseconds (as ROS logs stamp them)"},
                                          {1e6, "us", "microseconds"}, {1e3, "ms", "milliseconds"}}) {
    const double period = median_step / scale;
    if (period >= kShortestSamplePeriod && period <= kLongestSamplePeriod) {
      std::ostringstream text;
      text << "; if t is in " << name << ", that is a period of " << period << " s: give the time unit ("
           << "--time-unit " << unit << ", or time_unit=" << unit << " in the API)";
      return text.str();
    }
  }
  return {};
}

}  // namespace manipid

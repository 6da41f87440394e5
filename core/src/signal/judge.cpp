// judge.cpp — the neutral judge's states, low-pass, span and figures (signal/judge.h).
#include "manipid/core/signal/judge.h"

#include "manipid/core/errors.h"
#include "numbers.h"
#include "manipid/core/signal/butterworth.h"

#include <cmath>
#include <limits>
#include <string>

namespace manipid {
namespace {

constexpr int kJudgeOrder = 4;

/// np.gradient along the rows: central differences inside, one-sided at the two ends.
Eigen::MatrixXd gradient(const Eigen::MatrixXd& x, double dt) {
  const Eigen::Index N = x.rows();
  Eigen::MatrixXd d(N, x.cols());
  if (N < 2) return Eigen::MatrixXd::Zero(N, x.cols());
  for (Eigen::Index i = 1; i + 1 < N; ++i) d.row(i) = (x.row(i + 1) - x.row(i - 1)) / (2.0 * dt);
  d.row(0) = (x.row(1) - x.row(0)) / dt;
  d.row(N - 1) = (x.row(N - 1) - x.row(N - 2)) / dt;
  return d;
}

}  // namespace

void JudgeOptions::validate(double dt, double duration) const {
  const double nyquist = 0.5 / dt;
  if (!(cutoff_hz > 0.0 && cutoff_hz < nyquist)) {
    throw InputError("judge_cutoff", "the judge's low-pass cut-off must lie between 0 and the data's Nyquist frequency (" +
                                         detail::message_number(nyquist) + " Hz), not " + detail::message_number(cutoff_hz) + " Hz");
  }
  if (!(trim_seconds >= 0.0) || !std::isfinite(trim_seconds)) {
    throw InputError("judge_trim", "the judge's trim must be a number of seconds >= 0");
  }
  if (duration - 2.0 * trim_seconds < 8.0 * dt) {
    throw InputError("judge_trim", "the judge trims " + detail::message_number(trim_seconds) + " s at each end of a run of " +
                                       detail::message_number(duration) + " s: nothing would be left to compare");
  }
}

JudgedStates judge_states(const Trajectory& uniform, const JudgeOptions& options) {
  const double dt = uniform.dt();
  JudgedStates states;
  states.q = judge_lowpass(uniform.q, dt, options);
  states.qd = gradient(states.q, dt);
  states.qdd = gradient(states.qd, dt);
  return states;
}

Eigen::MatrixXd judge_lowpass(const Eigen::Ref<const Eigen::MatrixXd>& x, double dt, const JudgeOptions& options) {
  return filtfilt_columns(butterworth_lowpass(kJudgeOrder, options.cutoff_hz, dt), x);
}

JudgedSpan judged_span(const Eigen::Ref<const Eigen::VectorXd>& t, const JudgeOptions& options) {
  JudgedSpan span;
  const Eigen::Index N = t.size();
  if (N == 0) return span;
  const double from = t[0] + options.trim_seconds, to = t[N - 1] - options.trim_seconds;
  span.first = 0;
  while (span.first < N && t[span.first] < from) ++span.first;
  span.last = N - 1;
  while (span.last >= 0 && t[span.last] > to) --span.last;
  return span;
}

TorqueScore judge_torque(const Eigen::Ref<const Eigen::VectorXd>& t, const Eigen::Ref<const Eigen::MatrixXd>& measured,
                         const Eigen::Ref<const Eigen::MatrixXd>& predicted, const std::vector<int>& joints,
                         const JudgeOptions& options) {
  std::vector<int> columns = joints;
  if (columns.empty()) {
    for (int k = 0; k < measured.cols(); ++k) columns.push_back(k);
  }
  const double dt = t.size() > 1 ? (t[t.size() - 1] - t[0]) / static_cast<double>(t.size() - 1) : 1.0;
  options.validate(dt, t.size() > 1 ? t[t.size() - 1] - t[0] : 0.0);
  const Eigen::Index J = static_cast<Eigen::Index>(columns.size());
  Eigen::MatrixXd m(measured.rows(), J), p(predicted.rows(), J);
  for (Eigen::Index j = 0; j < J; ++j) {
    m.col(j) = measured.col(columns[static_cast<std::size_t>(j)]);
    p.col(j) = predicted.col(columns[static_cast<std::size_t>(j)]);
  }
  const JudgedSpan span = judged_span(t, options);
  return score_judged(t.segment(span.first, span.size()), judge_lowpass(m, dt, options).middleRows(span.first, span.size()),
                      judge_lowpass(p, dt, options).middleRows(span.first, span.size()));
}

TorqueScore score_judged(Eigen::VectorXd t, Eigen::MatrixXd measured, Eigen::MatrixXd predicted) {
  TorqueScore score;
  score.t = std::move(t);
  score.measured = std::move(measured);
  score.predicted = std::move(predicted);
  const Eigen::MatrixXd error = score.predicted - score.measured;
  const Eigen::Index J = error.cols();
  const double count = static_cast<double>(std::max<Eigen::Index>(error.rows(), 1));
  score.rms_error = (error.colwise().squaredNorm() / count).cwiseSqrt().transpose();
  score.relative_error.resize(J);
  for (Eigen::Index j = 0; j < J; ++j) {
    const double norm = score.measured.col(j).norm();
    score.relative_error[j] = norm > 0 ? error.col(j).norm() / norm : std::numeric_limits<double>::quiet_NaN();
  }
  const double total = score.measured.norm();
  score.overall_relative_error = total > 0 ? error.norm() / total : std::numeric_limits<double>::quiet_NaN();
  return score;
}

}  // namespace manipid

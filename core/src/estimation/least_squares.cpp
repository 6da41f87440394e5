// least_squares.cpp — Levenberg–Marquardt with bounds, the "LM" algorithm (least_squares.h).
#include "estimation/least_squares.h"
#include "numbers.h"

#include <Eigen/SVD>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace manipid::detail {

namespace {

using Clock = std::chrono::steady_clock;

// Nielsen's damping update (Madsen, Nielsen & Tingleff, "Methods for non-linear least squares
// problems", 2004, §3.2): the start λ is this fraction of the largest scaled curvature (1 after
// Marquardt's scaling); a step is taken when it achieves this share of the predicted reduction.
constexpr double kInitialDamping = 1e-3;
constexpr double kAcceptRatio = 1e-4;
constexpr int kMaxRejections = 60;  // λ grows at least 2× per rejection: 2^60 ends any stall

struct Point {
  Eigen::VectorXd x;         // scaled free parameters
  Eigen::VectorXd residual;  // r(θ)
  Eigen::MatrixXd jacobian;  // ∂r/∂x, free columns, scaled
  double cost = 0.0;
};

class Solver {
 public:
  Solver(const LeastSquaresFunction& function, const Eigen::VectorXd& initial, const MinimizeSettings& settings)
      : function_(function), settings_(settings), theta_(initial), best_theta_(initial), started_(Clock::now()) {
    for (int i = 0; i < initial.size(); ++i) {
      if (settings.free[i]) free_index_.push_back(i);
    }
    const int p = static_cast<int>(free_index_.size());
    scale_.resize(p);
    lower_.resize(p);
    upper_.resize(p);
    for (int a = 0; a < p; ++a) {
      const int k = free_index_[a];
      scale_[a] = initial[k] != 0.0 ? std::abs(initial[k]) : 1.0;
      lower_[a] = settings.lower[k] / scale_[a];
      upper_[a] = settings.upper[k] / scale_[a];
    }
  }

  MinimizeOutcome run() {
    const int p = static_cast<int>(free_index_.size());
    Eigen::VectorXd x0(p);
    for (int a = 0; a < p; ++a) x0[a] = theta_[free_index_[a]] / scale_[a];
    Point current;
    if (!evaluate(x0, current)) {
      // Stopped before the first evaluation (cancelled, no budget): the start's cost, unrecorded.
      Eigen::VectorXd residual;
      function_.residual(theta_, residual, nullptr);
      first_cost_ = best_cost_ = residual.squaredNorm() + function_.offset;
      return finish();
    }
    if (!std::isfinite(current.cost) || !current.jacobian.allFinite()) {
      stop_reason_ = "non_finite_start";
      return finish();
    }
    Eigen::VectorXd column_scale = Eigen::VectorXd::Zero(p);
    double damping = -1.0;
    double growth = 2.0;
    const double xtol = settings_.relative_x_tolerance;
    const double ftol = settings_.relative_f_tolerance;
    Point candidate;
    while (stop_reason_.empty()) {
      const Eigen::VectorXd gradient = current.jacobian.transpose() * current.residual;  // half of ∂cost/∂x
      // Held this step: parameters on a bound that the cost would push through it.
      std::vector<int> moving;
      for (int a = 0; a < p; ++a) {
        const bool held = (current.x[a] <= lower_[a] && gradient[a] > 0) || (current.x[a] >= upper_[a] && gradient[a] < 0);
        if (!held && gradient[a] != 0.0) moving.push_back(a);
        column_scale[a] = std::max(column_scale[a], current.jacobian.col(a).norm());
      }
      if (moving.empty()) {
        stop_reason_ = "converged: gradient zero";
        break;
      }
      const int k = static_cast<int>(moving.size());
      Eigen::MatrixXd scaled(current.jacobian.rows(), k);
      for (int b = 0; b < k; ++b) {
        const double d = column_scale[moving[b]] > 0 ? column_scale[moving[b]] : 1.0;
        scaled.col(b) = current.jacobian.col(moving[b]) / d;
      }
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeThinU | Eigen::ComputeThinV);
      const Eigen::VectorXd& sigma = svd.singularValues();
      const Eigen::VectorXd projected = svd.matrixU().transpose() * current.residual;
      if (damping < 0) damping = kInitialDamping * std::max(sigma.size() ? sigma[0] * sigma[0] : 1.0, 1e-300);
      bool accepted = false;
      for (int rejection = 0; rejection < kMaxRejections && stop_reason_.empty(); ++rejection) {
        Eigen::VectorXd coefficients(sigma.size());
        for (Eigen::Index i = 0; i < sigma.size(); ++i) {
          coefficients[i] = -sigma[i] * projected[i] / (sigma[i] * sigma[i] + damping);
        }
        const Eigen::VectorXd solved = svd.matrixV() * coefficients;
        Eigen::VectorXd x = current.x;
        std::vector<int> clamped, unclamped;
        for (int b = 0; b < k; ++b) {
          const double d = column_scale[moving[b]] > 0 ? column_scale[moving[b]] : 1.0;
          const int a = moving[b];
          const double wanted = current.x[a] + solved[b] / d;
          x[a] = std::clamp(wanted, lower_[a], upper_[a]);
          (x[a] != wanted ? clamped : unclamped).push_back(b);
        }
        if (!clamped.empty() && !unclamped.empty()) {
          // A step cut off by a bound is no longer the model's minimum for the others: with the cut
          // parameters where the bound put them, the others' damped step is solved again against the
          // residual that move leaves (else the cut step fails, the damping grows, and the steps shrink
          // away from a minimum on the bound).
          Eigen::VectorXd residual = current.residual;
          for (int b : clamped) residual += current.jacobian.col(moving[b]) * (x[moving[b]] - current.x[moving[b]]);
          Eigen::MatrixXd rest(current.jacobian.rows(), static_cast<Eigen::Index>(unclamped.size()));
          for (std::size_t c = 0; c < unclamped.size(); ++c) rest.col(static_cast<Eigen::Index>(c)) = scaled.col(unclamped[c]);
          const Eigen::JacobiSVD<Eigen::MatrixXd> again(rest, Eigen::ComputeThinU | Eigen::ComputeThinV);
          const Eigen::VectorXd& s = again.singularValues();
          const Eigen::VectorXd u = again.matrixU().transpose() * residual;
          Eigen::VectorXd c(s.size());
          for (Eigen::Index i = 0; i < s.size(); ++i) c[i] = -s[i] * u[i] / (s[i] * s[i] + damping);
          const Eigen::VectorXd resolved = again.matrixV() * c;
          for (std::size_t i = 0; i < unclamped.size(); ++i) {
            const int a = moving[unclamped[i]];
            const double d = column_scale[a] > 0 ? column_scale[a] : 1.0;
            x[a] = std::clamp(current.x[a] + resolved[static_cast<Eigen::Index>(i)] / d, lower_[a], upper_[a]);
          }
        }
        const Eigen::VectorXd step = x - current.x;
        const double step_norm = step.norm();
        const bool tiny_step = step_norm <= xtol * (current.x.norm() + xtol);
        const double predicted = current.residual.squaredNorm() - (current.residual + current.jacobian * step).squaredNorm();
        if (tiny_step || !(predicted > 0)) {
          // Nothing left that the linear model can gain: the minimum, within rounding.
          stop_reason_ = "converged: relative step below " + message_number(xtol);
          break;
        }
        if (!evaluate(x, candidate)) break;
        const double actual = current.cost - candidate.cost;
        const bool usable = std::isfinite(candidate.cost) && candidate.jacobian.allFinite();
        const double ratio = usable ? actual / predicted : -1.0;
        if (ratio > kAcceptRatio) {
          const double relative_change = actual / std::max(current.cost, std::numeric_limits<double>::min());
          std::swap(current, candidate);
          damping *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3));
          growth = 2.0;
          accepted = true;
          if (relative_change <= ftol) stop_reason_ = "converged: relative cost change below " + message_number(ftol);
          break;
        }
        damping *= growth;
        growth *= 2.0;
      }
      if (!accepted && stop_reason_.empty()) stop_reason_ = "converged: relative step below " + message_number(xtol);
    }
    return finish();
  }

 private:
  /// One evaluation at scaled x; false (with the stop reason set) when a budget or cancel forbids it.
  bool evaluate(const Eigen::VectorXd& x, Point& point) {
    if (settings_.cancel && settings_.cancel->load(std::memory_order_relaxed)) {
      cancelled_ = true;
      stop_reason_ = "cancelled";
      return false;
    }
    if (evaluations_ >= settings_.max_evaluations) {
      stop_reason_ = "maxeval_reached";
      return false;
    }
    if (std::chrono::duration<double>(Clock::now() - started_).count() >= settings_.max_seconds) {
      stop_reason_ = "maxtime_reached";
      return false;
    }
    const int p = static_cast<int>(free_index_.size());
    for (int a = 0; a < p; ++a) theta_[free_index_[a]] = x[a] * scale_[a];
    function_.residual(theta_, point.residual, &full_jacobian_);
    point.x = x;
    point.cost = point.residual.squaredNorm() + function_.offset;
    point.jacobian.resize(full_jacobian_.rows(), p);
    for (int a = 0; a < p; ++a) point.jacobian.col(a) = full_jacobian_.col(free_index_[a]) * scale_[a];
    if (++evaluations_ == 1) first_cost_ = point.cost;
    if (point.cost < best_cost_) {
      best_cost_ = point.cost;
      best_theta_ = theta_;
    }
    if (settings_.log) settings_.log->record(point.cost, theta_);
    return true;
  }

  MinimizeOutcome finish() const {
    MinimizeOutcome outcome;
    outcome.theta = best_theta_;
    outcome.cost = std::isfinite(best_cost_) ? best_cost_ : first_cost_;
    outcome.initial_cost = first_cost_;
    outcome.evaluations = evaluations_;
    outcome.stop_reason = stop_reason_;
    outcome.cancelled = cancelled_;
    return outcome;
  }

  const LeastSquaresFunction& function_;
  const MinimizeSettings& settings_;
  std::vector<int> free_index_;
  Eigen::VectorXd scale_, lower_, upper_;
  Eigen::VectorXd theta_, best_theta_;
  Eigen::MatrixXd full_jacobian_;
  double best_cost_ = std::numeric_limits<double>::infinity();
  double first_cost_ = std::numeric_limits<double>::quiet_NaN();
  long evaluations_ = 0;
  bool cancelled_ = false;
  std::string stop_reason_;
  Clock::time_point started_;
};

}  // namespace

MinimizeOutcome minimize_least_squares(const LeastSquaresFunction& function, const Eigen::VectorXd& initial,
                                       const MinimizeSettings& settings) {
  return Solver(function, initial, settings).run();
}

}  // namespace manipid::detail

// optimizer.h — internal: the minimisers behind one small interface, for every identification method
// and the excitation design (robot/excitation_design.cpp).
//
// minimize() runs an NLopt algorithm (optimizer.cpp) or, for "LM", Levenberg–Marquardt on a cost
// given as a sum of squares (least_squares.h); the callers do not branch on which. The NLopt path is
// core's one NLopt adapter and owns what NLopt 2.7.1 needs handled with care: fixed parameters are
// removed from the vector (2.7.1 ignores force_stop when a parameter is pinned by equal bounds), the
// nlopt::opt is built in place and never copied after its objective is set, and exceptions from
// NLopt are turned into a stop reason. Parameters are scaled by their start values so that kg and
// m look alike to the optimiser (unless the caller's coordinates are alike already: scale_by_start).
#pragma once

#include "manipid/core/errors.h"
#include "manipid/core/estimation/history.h"

#include <Eigen/Core>

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace manipid::detail {

using estimation::HistoryRecord;

/// Keeps a bounded history: every stride-th record, plus the first, the best and the last.
class HistoryRecorder {
 public:
  explicit HistoryRecorder(int limit) : limit_(limit < 3 ? 3 : limit) {}
  void add(long index, double cost, const Eigen::VectorXd& theta);
  std::vector<HistoryRecord> records() const;

 private:
  int limit_;
  long stride_ = 1;
  std::vector<HistoryRecord> kept_;
  HistoryRecord best_, last_;
  bool any_ = false;
};

/// The one owner of "an evaluation happened": it numbers each evaluation (across every stage of an
/// identification: optimiser, polish, output-error fit), keeps it in the bounded history, and tells the
/// caller's callback (the service streams it to the store).
class EvaluationLog {
 public:
  using Callback = std::function<void(long index, double cost, const Eigen::VectorXd& theta)>;
  EvaluationLog(int history_limit, Callback callback) : history_(history_limit), callback_(std::move(callback)) {}
  /// Records one evaluation; returns its index.
  long record(double cost, const Eigen::VectorXd& theta) {
    const long index = count_++;
    history_.add(index, cost, theta);
    if (callback_) callback_(index, cost, theta);
    return index;
  }
  long count() const { return count_; }
  std::vector<HistoryRecord> records() const { return history_.records(); }

 private:
  HistoryRecorder history_;
  Callback callback_;
  long count_ = 0;
};

/// θ (all parameters) → cost, and ∂cost/∂θ when `gradient` is not null.
using CostFunction = std::function<double(const Eigen::VectorXd& theta, Eigen::VectorXd* gradient)>;

/// A cost of the form |r(θ)|² + offset: θ (all parameters) → r, and ∂r/∂θ (rows × all parameters) when
/// `jacobian` is not null. Its value must equal the CostFunction's at every θ.
struct LeastSquaresFunction {
  std::function<void(const Eigen::VectorXd& theta, Eigen::VectorXd& residual, Eigen::MatrixXd* jacobian)> residual;
  double offset = 0.0;
};

/// The least-squares algorithm's name (Levenberg–Marquardt, least_squares.h).
inline constexpr const char* kLeastSquaresAlgorithm = "LM";

struct MinimizeSettings {
  std::string algorithm = "LN_BOBYQA";
  std::vector<bool> free;        // per parameter
  Eigen::VectorXd lower, upper;  // θ bounds, all parameters
  /// Stop rules: a step that changes x by less than this relative to |x| (x: the optimiser's
  /// coordinates, see scale_by_start), a step that changes the cost by less than this relative to
  /// it. NLopt takes 0 as off (LM: least_squares.h).
  double relative_x_tolerance = 1e-10;
  double relative_f_tolerance = 1e-14;
  int max_evaluations = 20000;
  double max_seconds = 120.0;
  const std::atomic<bool>* cancel = nullptr;
  EvaluationLog* log = nullptr;  // every evaluation is recorded here (numbers continue across stages)

  // The NLopt algorithms only ("LM" has its own scaling, steps and stops, and ignores these):
  /// The optimiser moves x_i = θ_i / |θ_i at the start| (1 where that is 0), so that kg and m look
  /// alike; false: x = θ, for a caller whose coordinates are alike already.
  bool scale_by_start = true;
  /// First steps of a derivative-free algorithm, θ units, one per parameter (fixed ones ignored);
  /// empty: 1 % of each scaled parameter, at most half its room to the nearer bound.
  Eigen::VectorXd initial_step;
  /// Stop rules, each off at 0: a step that changes every θ_i by less than this (θ units), a step
  /// that changes the cost by less than this (cost units).
  double absolute_x_tolerance = 0.0;
  double absolute_f_tolerance = 0.0;
  /// Asked before every evaluation, after `cancel`: true ends the run there, that evaluation not
  /// made (outcome.stopped; stop reason "stopped"). For stop rules the caller keeps itself (budgets
  /// shared between runs, a reason of its own): given, the adapter makes no evaluation beyond those
  /// NLopt asks for. Empty: never asked.
  std::function<bool()> stop;
};

struct MinimizeOutcome {
  Eigen::VectorXd theta;
  /// The best cost evaluated and the first one; with no evaluation made, the start's (evaluated
  /// then), or NaN when `stop` is given (the adapter evaluates nothing of its own then).
  double cost = 0.0;
  double initial_cost = 0.0;
  long evaluations = 0;  // this stage's
  std::string stop_reason;
  bool cancelled = false;
  bool stopped = false;                // settings.stop ended the run
  std::optional<std::string> failure;  // NLopt failed: what it said (stop_reason is "failure: " and this)
};

/// Throws InputError("algorithm") for an unknown or unsuitable algorithm name. "LM" uses derivatives.
bool algorithm_uses_gradient(const std::string& algorithm);
/// `least_squares`, when given, is the same cost as a sum of squares; "LM" needs it (InputError otherwise).
MinimizeOutcome minimize(const CostFunction& cost, const Eigen::VectorXd& initial, const MinimizeSettings& settings,
                         const LeastSquaresFunction* least_squares = nullptr);

}  // namespace manipid::detail

// optimizer.cpp — core's one NLopt adapter (identification, excitation design), and the dispatch to least
// squares (optimizer.h).
#include "estimation/optimizer.h"

#include "estimation/least_squares.h"

#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace manipid::detail {

void HistoryRecorder::add(long index, double cost, const Eigen::VectorXd& theta) {
  HistoryRecord record{index, cost, theta};
  if (!any_ || cost < best_.cost) best_ = record;
  last_ = record;
  if (!any_ || index % stride_ == 0) kept_.push_back(record);
  any_ = true;
  // Full: keep every other stored record (the first is always index 0 of kept_).
  if (static_cast<int>(kept_.size()) > limit_ - 2) {
    stride_ *= 2;
    std::vector<HistoryRecord> thinned;
    for (std::size_t i = 0; i < kept_.size(); ++i) {
      if (i == 0 || kept_[i].index % stride_ == 0) thinned.push_back(kept_[i]);
    }
    kept_ = std::move(thinned);
  }
}

std::vector<HistoryRecord> HistoryRecorder::records() const {
  std::vector<HistoryRecord> all = kept_;
  if (!any_) return all;
  for (const HistoryRecord& extra : {best_, last_}) {
    const bool present = std::any_of(all.begin(), all.end(), [&](const HistoryRecord& r) { return r.index == extra.index; });
    if (!present) all.push_back(extra);
  }
  std::sort(all.begin(), all.end(), [](const HistoryRecord& a, const HistoryRecord& b) { return a.index < b.index; });
  return all;
}

namespace {

struct AlgorithmName {
  const char* name;
  nlopt::algorithm algorithm;
  bool gradient;
};
constexpr AlgorithmName kAlgorithms[] = {
    {"LN_BOBYQA", nlopt::LN_BOBYQA, false},       {"LN_NELDERMEAD", nlopt::LN_NELDERMEAD, false},
    {"LN_SBPLX", nlopt::LN_SBPLX, false},         {"LD_LBFGS", nlopt::LD_LBFGS, true},
    {"LD_SLSQP", nlopt::LD_SLSQP, true},
};

const AlgorithmName& find_algorithm(const std::string& name) {
  for (const auto& candidate : kAlgorithms) {
    if (name == candidate.name) return candidate;
  }
  std::string known = kLeastSquaresAlgorithm;
  for (const auto& candidate : kAlgorithms) known += std::string(known.empty() ? "" : ", ") + candidate.name;
  throw InputError("algorithm", "unknown algorithm '" + name + "' (known: " + known + ")");
}

std::string result_name(nlopt::result result) {
  switch (result) {
    case nlopt::SUCCESS: return "success";
    case nlopt::STOPVAL_REACHED: return "stopval_reached";
    case nlopt::FTOL_REACHED: return "ftol_reached";
    case nlopt::XTOL_REACHED: return "xtol_reached";
    case nlopt::MAXEVAL_REACHED: return "maxeval_reached";
    case nlopt::MAXTIME_REACHED: return "maxtime_reached";
    case nlopt::ROUNDOFF_LIMITED: return "roundoff_limited";
    case nlopt::FORCED_STOP: return "cancelled";
    default: return "failure";
  }
}

struct Context {
  const CostFunction* cost;
  const MinimizeSettings* settings;
  std::vector<int> free_index;   // optimiser coordinate → θ index
  Eigen::VectorXd scale;         // θ_i = x_i · scale_i for free i
  Eigen::VectorXd theta;         // working θ (fixed entries stay)
  Eigen::VectorXd gradient;
  Eigen::VectorXd best_theta;
  double best_cost = std::numeric_limits<double>::infinity();
  double first_cost = std::numeric_limits<double>::quiet_NaN();
  long evaluations = 0;
  bool cancelled = false;
  bool stopped = false;
};

double objective(unsigned dimension, const double* x, double* gradient_out, void* data) {
  Context& context = *static_cast<Context*>(data);
  const MinimizeSettings& settings = *context.settings;
  if (settings.cancel && settings.cancel->load(std::memory_order_relaxed)) {
    context.cancelled = true;
    throw nlopt::forced_stop();
  }
  if (settings.stop && settings.stop()) {
    context.stopped = true;
    throw nlopt::forced_stop();
  }
  for (unsigned i = 0; i < dimension; ++i) context.theta[context.free_index[i]] = x[i] * context.scale[i];
  const double cost = (*context.cost)(context.theta, gradient_out ? &context.gradient : nullptr);
  if (gradient_out) {
    for (unsigned i = 0; i < dimension; ++i) gradient_out[i] = context.gradient[context.free_index[i]] * context.scale[i];
  }
  if (++context.evaluations == 1) context.first_cost = cost;
  if (cost < context.best_cost) {
    context.best_cost = cost;
    context.best_theta = context.theta;
  }
  if (settings.log) settings.log->record(cost, context.theta);
  if (!std::isfinite(cost)) {
    // Nothing can be learnt from a start without a cost: stop at once, the caller says why.
    if (context.evaluations == 1) throw nlopt::forced_stop();
    // Later, a point where the model overflows is one to move away from: NLopt's models
    // take +inf as "worse than anything", NaN would poison them.
    if (gradient_out) std::fill(gradient_out, gradient_out + dimension, 0.0);
    return std::numeric_limits<double>::infinity();
  }
  return cost;
}

MinimizeOutcome minimize_nlopt(const CostFunction& cost, const Eigen::VectorXd& initial, const MinimizeSettings& settings) {
  const AlgorithmName& algorithm = find_algorithm(settings.algorithm);
  Context context;
  context.cost = &cost;
  context.settings = &settings;
  context.theta = initial;
  context.best_theta = initial;
  context.gradient = Eigen::VectorXd::Zero(initial.size());
  for (int i = 0; i < initial.size(); ++i) {
    if (settings.free[i]) context.free_index.push_back(i);
  }
  const unsigned dimension = static_cast<unsigned>(context.free_index.size());
  MinimizeOutcome outcome;
  context.scale.resize(dimension);
  std::vector<double> x(dimension), lower(dimension), upper(dimension);
  for (unsigned i = 0; i < dimension; ++i) {
    const int k = context.free_index[i];
    context.scale[i] = settings.scale_by_start && initial[k] != 0.0 ? std::abs(initial[k]) : 1.0;
    x[i] = initial[k] / context.scale[i];
    lower[i] = settings.lower[k] / context.scale[i];
    upper[i] = settings.upper[k] / context.scale[i];
  }

  nlopt::opt optimizer(algorithm.algorithm, dimension);  // built in place, never copied
  optimizer.set_min_objective(objective, &context);
  optimizer.set_lower_bounds(lower);
  optimizer.set_upper_bounds(upper);
  optimizer.set_xtol_rel(settings.relative_x_tolerance);
  optimizer.set_ftol_rel(settings.relative_f_tolerance);
  optimizer.set_maxeval(settings.max_evaluations);
  optimizer.set_maxtime(settings.max_seconds);
  if (settings.absolute_x_tolerance > 0.0) {
    std::vector<double> tolerance(dimension);
    for (unsigned i = 0; i < dimension; ++i) tolerance[i] = settings.absolute_x_tolerance / context.scale[i];
    optimizer.set_xtol_abs(tolerance);
  }
  if (settings.absolute_f_tolerance > 0.0) optimizer.set_ftol_abs(settings.absolute_f_tolerance);
  if (!algorithm.gradient) {
    std::vector<double> step(dimension);
    for (unsigned i = 0; i < dimension; ++i) {
      if (settings.initial_step.size() != 0) {
        step[i] = settings.initial_step[context.free_index[i]] / context.scale[i];
        continue;
      }
      // A 1 % first step: the scaled parameters are all near 1.
      const double room = std::min(upper[i] - x[i], x[i] - lower[i]);
      step[i] = std::isfinite(room) && room > 0 ? std::min(0.01, 0.5 * room) : 0.01;
    }
    optimizer.set_initial_step(step);
  }
  if (algorithm.algorithm == nlopt::LD_LBFGS) optimizer.set_vector_storage(20);

  double final_cost = 0.0;
  try {
    outcome.stop_reason = result_name(optimizer.optimize(x, final_cost));
  } catch (const nlopt::forced_stop&) {
    outcome.stop_reason = "cancelled";
  } catch (const nlopt::roundoff_limited&) {
    outcome.stop_reason = "roundoff_limited";  // NLopt: the result is typically still useful
  } catch (const std::exception& error) {
    outcome.failure = error.what();
    outcome.stop_reason = "failure: " + *outcome.failure;
  }
  outcome.cancelled = context.cancelled;
  outcome.stopped = context.stopped;
  if (context.cancelled) outcome.stop_reason = "cancelled";
  if (context.stopped) outcome.stop_reason = "stopped";
  if (context.evaluations > 0 && !std::isfinite(context.first_cost)) outcome.stop_reason = "non_finite_start";
  // Report the best point evaluated: NLopt's x is not always the best after a forced stop.
  outcome.theta = context.best_theta;
  if (context.evaluations > 0) {
    outcome.cost = context.best_cost;
    outcome.initial_cost = context.first_cost;
  } else {
    // The start's cost, evaluated now; not for a caller that counts every evaluation itself (`stop`).
    outcome.cost = settings.stop ? std::numeric_limits<double>::quiet_NaN() : cost(initial, nullptr);
    outcome.initial_cost = outcome.cost;
  }
  outcome.evaluations = context.evaluations;
  return outcome;
}

}  // namespace

bool algorithm_uses_gradient(const std::string& algorithm) {
  return algorithm == kLeastSquaresAlgorithm || find_algorithm(algorithm).gradient;
}

MinimizeOutcome minimize(const CostFunction& cost, const Eigen::VectorXd& initial, const MinimizeSettings& settings,
                         const LeastSquaresFunction* least_squares) {
  const bool use_least_squares = settings.algorithm == kLeastSquaresAlgorithm;
  if (use_least_squares && !least_squares) {
    throw InputError("algorithm", std::string(kLeastSquaresAlgorithm) + " needs a cost that is a sum of squares with its Jacobian");
  }
  if (!use_least_squares) find_algorithm(settings.algorithm);  // unknown names fail before any evaluation
  if (std::none_of(settings.free.begin(), settings.free.end(), [](bool free) { return free; })) {
    MinimizeOutcome outcome;
    outcome.theta = initial;
    outcome.cost = outcome.initial_cost = cost(initial, nullptr);
    outcome.evaluations = 1;
    outcome.stop_reason = "no_free_parameters";
    return outcome;
  }
  return use_least_squares ? minimize_least_squares(*least_squares, initial, settings) : minimize_nlopt(cost, initial, settings);
}

}  // namespace manipid::detail

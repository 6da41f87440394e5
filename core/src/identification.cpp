// identification.cpp — identify(): validation, the three methods, and the result (identification.h).
#include "manipid/core/identification.h"

#include "filter_choice.h"
#include "manipid/core/input_error.h"
#include "manipid/core/output_error.h"
#include "optimizer.h"
#include "output_error_fit.h"
#include "uncertainty.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace manipid {

const char* to_string(IdentificationMethod method) {
  switch (method) {
    case IdentificationMethod::output_error: return "output-error";
    case IdentificationMethod::two_stage: return "two-stage";
    default: return "input-error";
  }
}

IdentificationMethod parse_identification_method(const std::string& text, const std::string& field) {
  if (text == "input-error") return IdentificationMethod::input_error;
  if (text == "output-error") return IdentificationMethod::output_error;
  if (text == "two-stage") return IdentificationMethod::two_stage;
  throw InputError(field, "unknown method '" + text + "' (expected input-error, output-error or two-stage)");
}

std::vector<std::string> identification_algorithms() {
  return {"LN_BOBYQA", "LN_NELDERMEAD", "LN_SBPLX", "LD_LBFGS", "LD_SLSQP"};
}

namespace {

using Clock = std::chrono::steady_clock;

struct Setup {
  int n = 0;
  std::vector<std::string> names;
  std::vector<bool> free;
  Eigen::VectorXd initial, lower, upper;
  bool use_reference = false;
};

Setup validate(const RobotModel& model, const Trajectory& data, const IdentificationOptions& options) {
  Setup setup;
  setup.n = model.joint_count();
  const int n = setup.n;
  data.validate();
  if (data.joint_count() != n) {
    throw InputError("q", "the data has " + std::to_string(data.joint_count()) + " joints, the model has " +
                              std::to_string(n));
  }
  check_parameters(model, options.initial);
  check_parameter_ranges(options.initial, "initial");
  setup.names = parameter_names(n);
  setup.initial = options.initial.vector();
  setup.free.assign(2 * n, options.free.empty());
  for (const std::string& name : options.free) {
    const int index = parameter_index(name, n);
    if (index < 0) {
      throw InputError("free", "unknown parameter '" + name + "' in the free list (this robot has m1..m" +
                                   std::to_string(n) + " and l1..l" + std::to_string(n) + ")");
    }
    setup.free[index] = true;
  }
  setup.lower = options.lower.size() ? options.lower : Eigen::VectorXd::Zero(2 * n);
  setup.upper = options.upper.size() ? options.upper
                                     : Eigen::VectorXd::Constant(2 * n, std::numeric_limits<double>::infinity());
  if (setup.lower.size() != 2 * n || setup.upper.size() != 2 * n) {
    throw InputError("bounds", "bounds need " + std::to_string(2 * n) + " entries (m1..mn, l1..ln)");
  }
  for (int i = 0; i < 2 * n; ++i) {
    if (std::isnan(setup.lower[i]) || std::isnan(setup.upper[i]) || setup.lower[i] > setup.upper[i]) {
      throw InputError(setup.names[i], "the bounds of " + setup.names[i] + " are not an interval");
    }
    if (setup.free[i] && (setup.initial[i] < setup.lower[i] || setup.initial[i] > setup.upper[i])) {
      std::ostringstream text;
      text << "the initial value of " << setup.names[i] << " (" << setup.initial[i] << ") is outside its bounds ["
           << setup.lower[i] << ", " << setup.upper[i] << "]";
      throw InputError(setup.names[i], text.str());
    }
  }
  const bool gradient = detail::algorithm_uses_gradient(options.algorithm);  // throws on unknown names
  const bool needs_simulation = options.method != IdentificationMethod::input_error;
  if (needs_simulation) {
    if (!data.has_reference()) {
      throw InputError("ref", std::string(to_string(options.method)) + " needs the reference: the data has no ref columns");
    }
    if (!options.controller) throw InputError("kp", std::string(to_string(options.method)) + " needs the PD gains kp and kd");
    if (options.method == IdentificationMethod::output_error && gradient) {
      throw InputError("algorithm", "output-error runs derivative-free algorithms only (LN_BOBYQA, LN_NELDERMEAD, LN_SBPLX)");
    }
  }
  if (options.controller && (options.controller->kp.size() != n || options.controller->kd.size() != n)) {
    throw InputError("kp", "kp and kd need " + std::to_string(n) + " entries, one per joint");
  }
  switch (options.torque_source) {
    case TorqueSource::measured:
      if (!data.has_torque()) throw InputError("tau", "the data has no tau columns");
      setup.use_reference = false;
      break;
    case TorqueSource::reference:
      setup.use_reference = true;
      break;
    case TorqueSource::automatic:
      setup.use_reference = !data.has_torque();
      break;
  }
  if (setup.use_reference && options.method != IdentificationMethod::output_error) {
    if (!data.has_reference()) throw InputError("tau", "the data has neither tau nor ref columns");
    if (!options.controller) throw InputError("kp", "the data has no tau columns: forming the torque from ref needs kp and kd");
  }
  if (options.max_evaluations < 1) throw InputError("max_evaluations", "max_evaluations must be at least 1");
  if (!(options.max_seconds > 0)) throw InputError("max_seconds", "max_seconds must be positive");
  return setup;
}

detail::MinimizeSettings minimize_settings(const IdentificationOptions& options, const Setup& setup,
                                           detail::EvaluationLog& log) {
  detail::MinimizeSettings settings;
  settings.algorithm = options.algorithm;
  settings.free = setup.free;
  settings.lower = setup.lower;
  settings.upper = setup.upper;
  settings.relative_x_tolerance = options.relative_x_tolerance;
  settings.relative_f_tolerance = options.relative_f_tolerance;
  settings.max_evaluations = options.max_evaluations;
  settings.max_seconds = options.max_seconds;
  settings.cancel = options.cancel;
  settings.log = &log;
  return settings;
}

int count_free(const std::vector<bool>& free) { return static_cast<int>(std::count(free.begin(), free.end(), true)); }

void apply_outcome(IdentificationResult& result, const detail::MinimizeOutcome& outcome) {
  result.estimate = outcome.theta;
  result.initial_cost = outcome.initial_cost;
  result.final_cost = outcome.cost;
  result.stop_reason = outcome.stop_reason;
  result.cancelled = outcome.cancelled;
}

void apply_uncertainty(IdentificationResult& result, const detail::Uncertainty& uncertainty) {
  result.std_errors = uncertainty.std_errors;
  result.correlation = uncertainty.correlation;
  result.identifiability = uncertainty.report;
  if (!uncertainty.unavailable.empty()) {
    result.warnings.push_back("no standard errors or identifiability report: " + uncertainty.unavailable);
  }
}

std::string describe_value(double value) {
  return std::isnan(value) ? "not a number (NaN)" : value > 0 ? "infinite" : "-infinite";
}

/// A cost that is not a finite number leaves nothing to estimate: fail with the reason.
void require_finite_costs(const IdentificationResult& result) {
  if (!std::isfinite(result.initial_cost)) {
    throw IdentificationError(
        "the cost at the starting values is " + describe_value(result.initial_cost) +
        ": the model's torque or the filtered data overflow there; check the initial values and the data's "
        "sample period and units");
  }
  if (!std::isfinite(result.final_cost)) {
    throw IdentificationError("the cost at the end of the search is " + describe_value(result.final_cost) +
                              "; narrow the bounds (lower/upper) around physically meaningful values");
  }
}

// Gauss–Newton polish of an input-error minimum. The Gram form makes each step exact and
// cheap (H = Gᵀ A G, g = Gᵀ A (β − β*)); steps are solved in relative coordinates with the
// unidentifiable directions truncated, so a derivative-free optimiser that stalled in the
// paper robot's flat m1/l1 valley or its narrow m3/m4/l4 one still ends at the minimum.
int refine_input_error(const InputErrorCost& cost, Eigen::VectorXd& theta, double& value, const Setup& setup,
                       const IdentificationOptions& options, detail::EvaluationLog& log) {
  std::vector<int> free_index;
  for (int i = 0; i < theta.size(); ++i) {
    if (setup.free[i]) free_index.push_back(i);
  }
  const int p = static_cast<int>(free_index.size());
  int steps = 0;
  for (int iteration = 0; iteration < 30 && p > 0; ++iteration) {
    if (options.cancel && options.cancel->load()) break;
    const Parameters parameters = Parameters::from_vector(theta);
    Eigen::VectorXd gradient;
    cost.evaluate(parameters, &gradient);
    const Eigen::MatrixXd information = cost.gauss_newton_matrix(parameters) / cost.data().samples();
    Eigen::VectorXd scale(p), g(p);
    Eigen::MatrixXd H(p, p);
    for (int a = 0; a < p; ++a) {
      scale[a] = std::max(std::abs(theta[free_index[a]]), 1e-12);
      g[a] = 0.5 * gradient[free_index[a]] * scale[a];
    }
    for (int a = 0; a < p; ++a)
      for (int b = 0; b < p; ++b) H(a, b) = scale[a] * information(free_index[a], free_index[b]) * scale[b];
    if (!H.allFinite() || !g.allFinite()) break;  // nothing to polish with; never NaN into a solver
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(H);
    const double largest = eigen.eigenvalues().maxCoeff();
    Eigen::VectorXd step = Eigen::VectorXd::Zero(p);
    for (int k = 0; k < p; ++k) {
      const double lambda = eigen.eigenvalues()[k];
      if (lambda > detail::kUnidentifiableRatio * detail::kUnidentifiableRatio * largest) {
        const Eigen::VectorXd v = eigen.eigenvectors().col(k);
        step -= v * (v.dot(g) / lambda);
      }
    }
    bool improved = false;
    for (double fraction = 1.0; fraction > 1e-3 && !improved; fraction *= 0.5) {
      Eigen::VectorXd candidate = theta;
      for (int a = 0; a < p; ++a) candidate[free_index[a]] += fraction * step[a] * scale[a];
      candidate = candidate.cwiseMax(setup.lower).cwiseMin(setup.upper);
      const double candidate_value = cost.evaluate(Parameters::from_vector(candidate));
      log.record(candidate_value, candidate);
      if (candidate_value < value) {
        const double change = (value - candidate_value) / std::max(value, 1e-300);
        theta = candidate;
        value = candidate_value;
        improved = true;
        ++steps;
        if (change < 1e-13) iteration = 30;
      }
    }
    if (!improved) break;
  }
  return steps;
}

/// What every method works on: the model, the prepared data, the options, the validated setup, the log.
struct Problem {
  const RobotModel& model;
  const Trajectory& data;
  const IdentificationOptions& options;
  const Setup& setup;
  detail::EvaluationLog& log;
};

/// The input-error stage (the paper's method; two-stage's first half): filter, minimise the Gram-form
/// cost, polish with Gauss–Newton. Leaves the cost for the uncertainty and the second stage.
struct InputErrorStage {
  detail::FilterChoice choice;
  FilteredData filtered;
  std::optional<InputErrorCost> cost;
};

InputErrorStage run_input_error(const Problem& problem, IdentificationResult& result) {
  const Setup& setup = problem.setup;
  const IdentificationOptions& options = problem.options;
  InputErrorStage stage;
  stage.choice = detail::choose_filter(problem.model, problem.data, options, setup.use_reference);
  result.filter = stage.choice.settings;
  result.filter_chosen_automatically = stage.choice.automatic;
  result.torque_source = setup.use_reference ? TorqueSource::reference : TorqueSource::measured;
  stage.filtered = filter_for_input_error(problem.data, stage.choice.settings, setup.use_reference, options.controller);
  Eigen::VectorXd weights;
  if (options.weighting == JointWeighting::inverse_variance) {
    weights.resize(setup.n);
    for (int j = 0; j < setup.n; ++j) {
      const double mean = stage.filtered.tau.col(j).mean();
      const double variance = (stage.filtered.tau.col(j).array() - mean).square().mean();
      weights[j] = variance > 0 ? 1.0 / variance : 1.0;
    }
  }
  stage.cost.emplace(problem.model, stage.filtered, weights);
  const InputErrorCost& cost = *stage.cost;
  const detail::CostFunction function = [&cost](const Eigen::VectorXd& theta, Eigen::VectorXd* gradient) {
    return cost.evaluate(Parameters::from_vector(theta), gradient);
  };
  apply_outcome(result, detail::minimize(function, setup.initial, minimize_settings(options, setup, problem.log)));
  require_finite_costs(result);
  if (options.refine && !result.cancelled) {
    result.refinement_steps = refine_input_error(cost, result.estimate, result.final_cost, setup, options, problem.log);
  }
  return stage;
}

/// The output-error methods see the identifiable directions through the exact input-error structure.
Eigen::MatrixXd identifiable_directions(const Problem& problem, const InputErrorCost& structure, const Eigen::VectorXd& at) {
  return detail::identifiable_basis(structure.gauss_newton_matrix(Parameters::from_vector(at)), at, problem.setup.free);
}

void assess_output_error(const Problem& problem, const OutputErrorCost& output_error, const InputErrorCost& structure,
                         const Eigen::VectorXd& residual, const Eigen::MatrixXd& jacobian, IdentificationResult& result) {
  result.simulations = output_error.simulations();
  const double dof =
      std::max(1.0, static_cast<double>(output_error.residual_count() - count_free(problem.setup.free)));
  const detail::UncertaintyInput uncertainty{
      .names = problem.setup.names,
      .theta = result.estimate,
      .free = problem.setup.free,
      .information = jacobian.transpose() * jacobian,
      .structure = structure.gauss_newton_matrix(Parameters::from_vector(result.estimate)),
      .residual_variance = residual.squaredNorm() / dof,
      .products = &structure.products()};
  apply_uncertainty(result, detail::assess_uncertainty(uncertainty));
}

void assess_input_error(const Problem& problem, const InputErrorStage& stage, IdentificationResult& result) {
  const Setup& setup = problem.setup;
  // σ² per residual, inflated by 1/Σc0² because low-passed residuals are correlated over
  // about π/Ωg samples (white noise through the filter keeps Σc0² of its variance).
  const double residual_sum = result.final_cost * stage.filtered.samples();
  const double dof = std::max(1.0, static_cast<double>(stage.cost->residual_count() - count_free(setup.free)));
  const double correlation_factor = 1.0 / cached_filter(stage.choice.settings)->coefficients(FilterOrder::lowpass).squaredNorm();
  const detail::UncertaintyInput uncertainty{
      .names = setup.names,
      .theta = result.estimate,
      .free = setup.free,
      .information = stage.cost->gauss_newton_matrix(Parameters::from_vector(result.estimate)),
      .structure = {},
      .residual_variance = residual_sum / dof * correlation_factor,
      .products = &stage.cost->products()};
  apply_uncertainty(result, detail::assess_uncertainty(uncertainty));
}

void identify_input_error(const Problem& problem, IdentificationResult& result) {
  const InputErrorStage stage = run_input_error(problem, result);
  assess_input_error(problem, stage, result);
  if (stage.choice.q_noise > 1e-7) {
    std::ostringstream text;
    text << "q carries measurement noise (about " << stage.choice.q_noise
         << " rad): input-error standard errors count torque noise but not the noise the filtered derivatives of "
            "q carry into the regressor (errors-in-variables), so they are optimistic and the estimates slightly "
            "biased; the two-stage method (--method two-stage) removes that bias";
    result.warnings.push_back(text.str());
  }
}

void identify_output_error(const Problem& problem, IdentificationResult& result) {
  const Setup& setup = problem.setup;
  const IdentificationOptions& options = problem.options;
  // The exact structure (which directions no data can see) comes from the Gram form.
  const FilterSettings structure_filter{100, 0.2, problem.data.dt()};
  const InputErrorCost structure(problem.model,
                                 filter_for_input_error(problem.data, structure_filter, true, options.controller));
  const Eigen::MatrixXd basis = identifiable_directions(problem, structure, setup.initial);
  const OutputErrorCost output_error(problem.model, problem.data, *options.controller, options.simulation_relative_tolerance);
  const detail::CostFunction function = [&output_error](const Eigen::VectorXd& theta, Eigen::VectorXd*) {
    return output_error.evaluate(Parameters::from_vector(theta));
  };
  apply_outcome(result, detail::minimize(function, setup.initial, minimize_settings(options, setup, problem.log)));
  require_finite_costs(result);
  if (result.cancelled) return;
  Eigen::VectorXd residual;
  output_error.evaluate(Parameters::from_vector(result.estimate), &residual);
  const Eigen::MatrixXd jacobian = detail::output_error_jacobian(output_error, result.estimate, residual, setup.free, basis);
  assess_output_error(problem, output_error, structure, residual, jacobian, result);
}

void identify_two_stage(const Problem& problem, IdentificationResult& result) {
  const Setup& setup = problem.setup;
  const IdentificationOptions& options = problem.options;
  const InputErrorStage stage = run_input_error(problem, result);
  if (result.cancelled) {  // stopped in the first stage: its figures are what there is
    assess_input_error(problem, stage, result);
    return;
  }
  const Eigen::MatrixXd basis = identifiable_directions(problem, *stage.cost, result.estimate);
  const OutputErrorCost output_error(problem.model, problem.data, *options.controller, options.simulation_relative_tolerance);
  const detail::FitBounds bounds{setup.n, setup.free, setup.lower, setup.upper};
  const detail::GaussNewtonOutcome outcome =
      detail::gauss_newton_output_error(output_error, result.estimate, basis, bounds, options, problem.log);
  result.estimate = outcome.theta;
  result.final_cost = outcome.cost;  // now the output-error cost, rad²
  result.stop_reason = outcome.stop_reason;
  result.cancelled = outcome.cancelled;
  require_finite_costs(result);
  assess_output_error(problem, output_error, *stage.cost, outcome.residual, outcome.jacobian, result);
}

}  // namespace

IdentificationResult identify(const RobotModel& model, const Trajectory& measured, const IdentificationOptions& options) {
  const auto started = Clock::now();
  IdentificationResult result;
  const Trajectory data = prepare_data(measured, options.preparation, &result.warnings);
  const Setup setup = validate(model, data, options);
  result.method = options.method;
  result.algorithm = options.algorithm;
  result.names = setup.names;
  result.free = setup.free;
  result.initial = setup.initial;
  detail::EvaluationLog log(options.history_limit, options.on_evaluation);
  const Problem problem{model, data, options, setup, log};
  // One function per method, as Ceres dispatches its minimisers.
  switch (options.method) {
    case IdentificationMethod::input_error: identify_input_error(problem, result); break;
    case IdentificationMethod::output_error: identify_output_error(problem, result); break;
    case IdentificationMethod::two_stage: identify_two_stage(problem, result); break;
  }
  require_finite_costs(result);
  if (result.std_errors.size() != result.estimate.size()) {  // cancelled before the uncertainty was assessed
    const int free_count = count_free(setup.free);
    result.std_errors = Eigen::VectorXd::Constant(result.estimate.size(), std::numeric_limits<double>::quiet_NaN());
    result.correlation = Eigen::MatrixXd::Constant(free_count, free_count, std::numeric_limits<double>::quiet_NaN());
  }
  result.evaluations = log.count();
  result.history = log.records();
  result.wall_seconds = std::chrono::duration<double>(Clock::now() - started).count();
  return result;
}

}  // namespace manipid

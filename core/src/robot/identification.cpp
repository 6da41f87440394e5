// identification.cpp — base parameters by linear least squares on the consistently filtered rows
// (robot/identification.h).
#include "manipid/core/robot/identification.h"

#include "manipid/core/errors.h"

#include <Eigen/QR>
#include <unsupported/Eigen/FFT>
#include <Eigen/SVD>

#include <algorithm>
#include <chrono>
#include <complex>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

namespace manipid::robot {
namespace {

using Clock = std::chrono::steady_clock;

/// Relative singular value below which a base direction counts as not excited by the data.
constexpr double kUnexcitedRatio = 1e-10;

std::string join(const std::vector<std::string>& words) {
  std::string text;
  for (std::size_t i = 0; i < words.size(); ++i) text += (i ? ", " : "") + words[i];
  return text;
}

/// The least-squares solve in scaled coordinates x = S β (S: column norms of the weighted rows).
struct Solution {
  Eigen::VectorXd beta;
  Eigen::MatrixXd covariance_scaled;  // (A_sᵀ A_s)⁺ restricted to the excited directions, times nothing
  Eigen::VectorXd scale;
  Eigen::VectorXd singular_values;    // of the scaled rows, largest first
  Eigen::MatrixXd null_directions;    // scaled coordinates, columns: directions not excited
};

Solution solve(const Eigen::MatrixXd& rows, const Eigen::VectorXd& target, const Eigen::VectorXd& row_weights,
               const Eigen::VectorXd& beta_prior) {
  const Eigen::Index b = rows.cols();
  Solution solution;
  Eigen::MatrixXd A = row_weights.asDiagonal() * rows;
  const Eigen::VectorXd y = row_weights.asDiagonal() * target;
  solution.scale = A.colwise().norm().transpose();
  for (Eigen::Index c = 0; c < b; ++c) {
    if (!(solution.scale[c] > 0.0)) solution.scale[c] = 1.0;  // an all-zero column: left to the prior below
  }
  A = A * solution.scale.cwiseInverse().asDiagonal();
  // QR first (rows × b → b × b), then an SVD of the small triangle: the singular values are A's.
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(b).triangularView<Eigen::Upper>();
  const Eigen::VectorXd z = (qr.householderQ().transpose() * y).head(b);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  solution.singular_values = svd.singularValues();
  const double largest = b > 0 ? solution.singular_values[0] : 0.0;
  int excited = 0;
  while (excited < b && solution.singular_values[excited] > kUnexcitedRatio * largest) ++excited;
  const Eigen::MatrixXd V = svd.matrixV();
  const Eigen::MatrixXd U = svd.matrixU();
  const Eigen::VectorXd prior_scaled = solution.scale.cwiseProduct(beta_prior);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(b);
  solution.covariance_scaled = Eigen::MatrixXd::Zero(b, b);
  for (int k = 0; k < excited; ++k) {
    const double sigma = solution.singular_values[k];
    x += V.col(k) * (U.col(k).dot(z) / sigma);
    solution.covariance_scaled += V.col(k) * V.col(k).transpose() / (sigma * sigma);
  }
  solution.null_directions = V.rightCols(b - excited);
  x += solution.null_directions * (solution.null_directions.transpose() * prior_scaled);  // unexcited: the prior
  solution.beta = x.cwiseQuotient(solution.scale);
  return solution;
}

/// Per-row weights from per-joint weights (rows are joint-major within each instant).
Eigen::VectorXd row_weights(const Eigen::VectorXd& joint_weights, Eigen::Index rows) {
  const Eigen::Index n = joint_weights.size();
  Eigen::VectorXd weights(rows);
  for (Eigen::Index r = 0; r < rows; ++r) weights[r] = joint_weights[r % n];
  return weights;
}

Eigen::VectorXd joint_residual_rms(const Eigen::VectorXd& residual, int n) {
  Eigen::VectorXd rms = Eigen::VectorXd::Zero(n);
  const Eigen::Index instants = residual.size() / n;
  for (Eigen::Index r = 0; r < residual.size(); ++r) rms[r % n] += residual[r] * residual[r];
  return (rms / static_cast<double>(std::max<Eigen::Index>(instants, 1))).cwiseSqrt();
}

/// The filters: each given one as given (half-length and band together), the others chosen.
FilterPair filters_for(const Trajectory& data, const IdentificationOptions& options, IdentificationResult& result) {
  if ((options.half_length > 0) != (options.band > 0.0)) {
    throw InputError(options.band > 0.0 ? "half_length" : "band",
                     "give the differentiation filter's half_length and band together, or neither (chosen from the data)");
  }
  if ((options.comparison_half_length > 0) != (options.comparison_band > 0.0)) {
    throw InputError(options.comparison_band > 0.0 ? "comparison_half_length" : "comparison_band",
                     "give the comparison filter's half_length and band together, or neither (chosen from the data)");
  }
  FilterPair filters;
  const bool both_given = options.half_length > 0 && options.comparison_half_length > 0;
  if (!both_given) {
    filters = choose_filters(data);
    result.filters_chosen_automatically = true;
    result.motion_band_hz = motion_band(data);
  }
  if (options.half_length > 0) filters.differentiation = FilterSettings{options.half_length, options.band, data.dt()};
  if (options.comparison_half_length > 0) {
    filters.comparison = FilterSettings{options.comparison_half_length, options.comparison_band, data.dt()};
  }
  return filters;
}

}  // namespace

ParameterStructure parameter_structure(const Model& model, const ParameterLayout& layout) {
  const int n = model.joint_count();
  ParameterStructure structure;
  structure.parameter_count = layout.size(n);
  structure.parameter_names = standard_parameter_names(n, layout);
  for (int k = 0; k < n; ++k) {
    structure.link_offsets.push_back(kInertialParametersPerBody * k);
    structure.link_names.push_back(model.joints[static_cast<std::size_t>(k)].link);
    for (int begin : {layout.viscous_begin(n), layout.coulomb_begin(n), layout.armature_begin(n)}) {
      if (begin >= 0) structure.non_negative.push_back(begin + k);
    }
  }
  std::sort(structure.non_negative.begin(), structure.non_negative.end());
  return structure;
}

double motion_band(const Trajectory& data, double tail) {
  const Eigen::Index N = data.samples();
  Eigen::Index size = 1;
  while (size < N) size *= 2;
  Eigen::FFT<double> fft;
  std::vector<double> signal(static_cast<std::size_t>(size), 0.0);
  std::vector<std::complex<double>> spectrum;
  Eigen::VectorXd power = Eigen::VectorXd::Zero(size / 2 + 1);
  for (int k = 0; k < data.joint_count(); ++k) {
    const Eigen::VectorXd q = data.q.col(k);
    const double first = q[0], last = q[N - 1];
    for (Eigen::Index i = 0; i < N; ++i) {
      const double x = static_cast<double>(i) / static_cast<double>(std::max<Eigen::Index>(N - 1, 1));
      const double hann = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * x);
      signal[static_cast<std::size_t>(i)] = (q[i] - first - (last - first) * x) * hann;
    }
    fft.fwd(spectrum, signal);
    for (Eigen::Index f = 0; f <= size / 2; ++f) power[f] += std::norm(spectrum[static_cast<std::size_t>(f)]);
  }
  const double total = power.sum();
  if (!(total > 0.0)) return 0.0;  // no motion at all
  double cumulative = 0.0;
  Eigen::Index f = 0;
  for (; f <= size / 2; ++f) {
    cumulative += power[f];
    if (cumulative >= (1.0 - tail) * total) break;
  }
  return static_cast<double>(std::min(f, size / 2)) / (static_cast<double>(size) * data.dt());
}

FilterPair choose_filters(const Trajectory& data) {
  const double dt = data.dt();
  const double nyquist_band = std::numbers::pi;
  // Ω_m: at least one frequency bin, so a motionless or very slow record still gets finite filters.
  const double resolution = 2.0 * std::numbers::pi / static_cast<double>(data.samples());
  const double motion = std::max(2.0 * std::numbers::pi * motion_band(data) * dt, resolution);
  const auto half_length = [](double band) { return std::max(2, static_cast<int>(std::ceil(6.4 * std::numbers::pi / band))); };
  FilterPair filters;
  filters.differentiation.dt = filters.comparison.dt = dt;
  filters.differentiation.band = std::min(nyquist_band / 2, 100.0 * motion);
  filters.differentiation.half_length = half_length(filters.differentiation.band);
  // The comparison filter's passband need not be flat (τ and the regressor go through the same one), only
  // its band matter: a shorter window, M_c = ⌈4π/Ω_c⌉, keeps more data and costs less.
  filters.comparison.band = std::min(filters.differentiation.band, 5.0 * motion);
  filters.comparison.half_length = std::max(2, static_cast<int>(std::ceil(4.0 * std::numbers::pi / filters.comparison.band)));
  // The filters consume M + M_c samples at each end; keep at least two thirds of the data.
  const int budget = std::max(2, (data.samples() / 3 - 3) / 2 - filters.differentiation.half_length);
  if (filters.comparison.half_length > budget) {
    filters.comparison.half_length = budget;
    filters.comparison.band = std::min(nyquist_band, 4.0 * std::numbers::pi / budget);
  }
  return filters;
}

IdentificationResult identify(const Model& model, const Trajectory& measured, const IdentificationOptions& options) {
  const auto started = Clock::now();
  const int n = model.joint_count();
  const ParameterLayout& layout = options.layout;
  const int p = layout.size(n);
  IdentificationResult result;
  result.standard_names = standard_parameter_names(n, layout);
  result.prior = options.prior.size() ? options.prior : standard_parameters(model, layout);
  if (result.prior.size() != p) {
    throw InputError("prior", "the prior has " + std::to_string(result.prior.size()) + " entries, the robot's standard "
                                  "vector " + std::to_string(p));
  }
  if (!result.prior.allFinite()) throw InputError("prior", "the prior holds a value that is not a finite number");
  if (measured.joint_count() != n) {
    throw InputError("q", "the data has " + std::to_string(measured.joint_count()) + " joints, the robot (" + model.name +
                              ") has " + std::to_string(n));
  }
  if (!measured.has_torque()) throw InputError("tau", "the data has no tau columns: identification needs measured torques");

  std::optional<Trajectory> prepared;  // only when trimming or resampling changes the data
  const Trajectory& data = prepare_data(measured, options.preparation, prepared, &result.warnings);
  result.base = base_parameters(model, layout, options.base);
  const BaseParameters& base = result.base;
  for (int index : base.absent) result.unidentifiable.push_back(result.standard_names[static_cast<std::size_t>(index)]);

  result.filters = filters_for(data, options, result);
  const FilteredRegressor rows = filtered_regressor(model, layout, data, result.filters, options.cancel);
  if (rows.instants == 0) {
    result.cancelled = true;
    result.wall_seconds = std::chrono::duration<double>(Clock::now() - started).count();
    return result;
  }
  result.decimation = rows.decimation;
  result.rows = static_cast<int>(rows.W.rows());
  const int b = base.size();
  if (result.rows < 2 * b) {
    throw InputError("samples", "after filtering, the data give " + std::to_string(rows.instants) + " instants x " +
                                    std::to_string(n) + " joints = " + std::to_string(result.rows) + " rows for " +
                                    std::to_string(b) + " base parameters (at least " + std::to_string(2 * b) +
                                    " are needed): give longer data or a wider comparison band");
  }
  Eigen::MatrixXd W_b(rows.W.rows(), b);
  for (int i = 0; i < b; ++i) W_b.col(i) = rows.W.col(base.independent[static_cast<std::size_t>(i)]);
  const Eigen::VectorXd beta_prior = base.combination * result.prior;

  // Unweighted first; per-joint weighting then divides each joint by its residual standard deviation.
  result.joint_weights = Eigen::VectorXd::Ones(n);
  Solution solution = solve(W_b, rows.tau, row_weights(result.joint_weights, W_b.rows()), beta_prior);
  if (options.weighting == JointWeighting::per_joint) {
    const Eigen::VectorXd rms = joint_residual_rms(rows.tau - W_b * solution.beta, n);
    for (int k = 0; k < n; ++k) result.joint_weights[k] = rms[k] > 0 ? 1.0 / rms[k] : 1.0;
    result.joint_weights /= result.joint_weights.maxCoeff();  // the largest weight 1: costs stay in N·m²
    solution = solve(W_b, rows.tau, row_weights(result.joint_weights, W_b.rows()), beta_prior);
  }
  result.estimate = solution.beta;

  const Eigen::VectorXd residual = rows.tau - W_b * result.estimate;
  result.residual_rms = joint_residual_rms(residual, n);
  const Eigen::Index excited = b - solution.null_directions.cols();
  const double dof = std::max<double>(1.0, static_cast<double>(residual.size() - excited));
  const Eigen::VectorXd weighted = row_weights(result.joint_weights, residual.size()).cwiseProduct(residual);
  result.residual_variance = residual.squaredNorm() / dof;
  // Filtered residuals are correlated: white noise through L keeps Σc² of its variance, and rows D apart
  // are about 1/(D Σc²) times less independent than white samples would be (never counted as more).
  const double correlation_factor = std::max(1.0, 1.0 / (rows.decimation * rows.lowpass_energy));
  const double weighted_variance = weighted.squaredNorm() / dof * correlation_factor;
  const Eigen::MatrixXd covariance = solution.scale.cwiseInverse().asDiagonal() * (weighted_variance * solution.covariance_scaled) *
                                     solution.scale.cwiseInverse().asDiagonal();
  result.std_errors = covariance.diagonal().cwiseSqrt();
  result.correlation = Eigen::MatrixXd::Constant(b, b, std::numeric_limits<double>::quiet_NaN());
  std::vector<bool> unexcited(static_cast<std::size_t>(b), false);
  for (int i = 0; i < b; ++i) {
    // A base parameter with a visible share in an unexcited direction has no standard error of its own.
    if (solution.null_directions.cols() > 0 && solution.null_directions.row(i).norm() > 0.05) {
      unexcited[static_cast<std::size_t>(i)] = true;
      result.std_errors[i] = std::numeric_limits<double>::quiet_NaN();
      result.unexcited.push_back(base.names[static_cast<std::size_t>(i)]);
    }
  }
  for (int i = 0; i < b; ++i) {
    for (int j = 0; j < b; ++j) {
      if (unexcited[static_cast<std::size_t>(i)] || unexcited[static_cast<std::size_t>(j)]) continue;
      result.correlation(i, j) = covariance(i, j) / std::sqrt(covariance(i, i) * covariance(j, j));
    }
  }
  result.condition_number = solution.null_directions.cols() > 0 || excited == 0
                                ? std::numeric_limits<double>::infinity()
                                : solution.singular_values[0] / solution.singular_values[excited - 1];
  if (!result.unexcited.empty()) {
    result.warnings.push_back("the data do not excite " + join(result.unexcited) +
                              ": these base parameters keep the prior's (URDF's) values; a richer excitation "
                              "(manipid excitation) would determine them");
  }

  // The standard vector with these base parameters nearest to the prior: π0 + Cᵀ(CCᵀ)⁻¹(β̂ − Cπ0).
  const Eigen::MatrixXd& C = base.combination;
  const Eigen::VectorXd correction = (C * C.transpose()).ldlt().solve(result.estimate - beta_prior);
  result.point = result.prior + C.transpose() * correction;

  const ParameterStructure structure = parameter_structure(model, layout);
  if (options.physical) {
    // The same rows and weights as the least squares, over every standard parameter.
    ConsistentFitProblem problem;
    const Eigen::VectorXd weights = row_weights(result.joint_weights, rows.W.rows());
    problem.R = weights.asDiagonal() * rows.W;
    problem.z = weights.asDiagonal() * rows.tau;
    problem.unconstrained = result.point;
    problem.prior = result.prior;
    ConsistentFitOptions fit_options;
    fit_options.cancel = options.cancel;
    // Weakly excited real arms (the KUKA log: condition 110) need a few hundred iterations from a very
    // inconsistent least-squares point; each costs O(p³) on the reduced problem, well under a millisecond.
    fit_options.max_iterations = 2000;
    result.physical = fit_consistent(structure, problem, fit_options);
    if (result.physical->termination == FitTermination::cancelled) {
      result.cancelled = true;
    } else {
      result.point = result.physical->estimate;
      result.estimate = C * result.point;
      result.residual_rms = joint_residual_rms(rows.tau - W_b * result.estimate, n);
      if (!result.physical->converged()) {
        result.warnings.push_back("the physically consistent fit did not converge: " + result.physical->message);
      }
    }
  }
  result.consistency = check_consistency(structure, result.point);
  result.wall_seconds = std::chrono::duration<double>(Clock::now() - started).count();
  return result;
}

ValidationReport validate(const Model& model, const ParameterLayout& layout, const IdentificationResult& result,
                          const Trajectory& data, const DataPreparation& preparation) {
  if (data.joint_count() != model.joint_count()) {
    throw InputError("q", "the validation data has " + std::to_string(data.joint_count()) + " joints, the robot (" +
                              model.name + ") has " + std::to_string(model.joint_count()));
  }
  if (!data.has_torque()) throw InputError("tau", "the validation data has no tau columns to compare the prediction with");
  ValidationReport report;
  DataPreparation same_grid = preparation;
  same_grid.uniform.dt = result.filters.differentiation.dt;  // the filters are built for this period
  std::optional<Trajectory> prepared;
  const Trajectory& uniform = prepare_data(data, same_grid, prepared, &report.warnings);
  report.estimate = predict_torque(model, layout, result.point, uniform, result.filters);
  report.prior = predict_torque(model, layout, result.prior, uniform, result.filters);
  return report;
}

}  // namespace manipid::robot

// consistent_fit.cpp — interior-point Levenberg–Marquardt over log-Cholesky links and bounded friction.
//
// Variables y have π's layout: a link's ten entries hold its log-Cholesky θ, every other entry
// holds the parameter itself (non-negative ones ≥ 0). π(y) is block-diagonal, so its Jacobian
// P is identity outside the links and one 10×10 block per link. Each stage minimises
//
//   F_μ(π) = ‖Rπ − z‖² + γ‖S⁻¹(π − π₀)‖² + μ Σ_k 2·B_k(π),
//   B_k = tr(A_c⁻¹A) − ln det(A_c⁻¹A) − 4,  A = J_k − F_k,  A_c = J_c,k − F_k,
//
// (F_k the margin J̃ ⪰ f·I written in J's units, J_c,k the barrier's centre, consistent_fit.h),
// with the model of each iteration Newton's in π pulled back through P:
//
//   ½F(π + Pδ) ≈ ½F(π) + gᵀδ + ½ δᵀ Pᵀ(RᵀR + γS⁻² + μ∇²B) P δ,   g = Pᵀ∇_π(½F).
//
// It drops only the chart's own curvature (the terms ∇_π F·∂²π/∂θ²), and the step is taken
// through π (θ_new = θ(π + Pδ)), where that curvature does not enter. An iteration costs
// O(p²·10 + p³/3) and never touches the samples.
//
// fit_consistent() checks the input (check_problem()) and runs a ConsistentFitMinimizer, a
// class with one method per step of the fit (its comment lists them); each stage of its barrier
// continuation is a run of core's one Levenberg–Marquardt minimiser (estimation/gauss_newton.h:
// the damping rule and the stop tests), the fit being its problem (the model, the damped step,
// the fraction to the boundary and the retraction through π).
#include "manipid/core/robot/consistent_fit.h"

#include "estimation/gauss_newton.h"
#include "robot/inertia_internal.h"
#include "manipid/core/errors.h"
#include "manipid/core/robot/log_cholesky.h"
#include "numbers.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace manipid::robot {
namespace {

using manipid::detail::kNaN;
using manipid::detail::kInfinity;
using manipid::detail::short_number;

using manipid::detail::GaussNewtonMinimizer;
using manipid::detail::GaussNewtonModel;
using manipid::detail::GaussNewtonOptions;
using manipid::detail::GaussNewtonStop;
// The continuation on the barrier weight μ: the cap on the first stage's weight relative to
// σ_max(R S)², the last stage's weight relative to γ (and, when γ = 0, to σ_max(R S)²), and the
// relative tolerances that end an intermediate stage.
constexpr double kFirstStageCap = 1e-2;
constexpr double kLastStageShare = 0.1;
constexpr double kLastStageFloor = 1e-14;
constexpr double kStageTolerance = 1e-4;
// A step goes at most this fraction of the way to the boundary of the feasible set along its
// direction (interior-point methods' fraction to the boundary).
constexpr double kFractionToBoundary = 0.95;
// The relative eigenvalue floor of the start's projection: 1e-2, a link at least about a tenth
// as thick as it is large. A start on the boundary is where the barrier's Newton model holds
// only for tiny steps; a centred start costs the continuation a third fewer iterations.
constexpr double kStartFloor = 1e-2;
// The fit keeps J̃ ⪰ f·I with f this fraction of the projection's floor (relative to the prior
// link's largest eigenvalue): a link projected at that floor is then strictly inside.
constexpr double kFitFloorShare = 0.1;

void require_finite(const Eigen::Ref<const Eigen::MatrixXd>& value, const char* field, const char* what) {
  if (!value.allFinite()) {
    throw InputError(field, std::string(field) + " has an entry that is not a finite number (" + what + ")");
  }
}

void require_size(const Eigen::VectorXd& value, Eigen::Index size, const char* field, const char* what) {
  if (value.size() != size) {
    throw InputError(field, std::string(field) + " must have " + std::to_string(size) + " entries (" + what +
                                "), got " + std::to_string(value.size()));
  }
}

void validate_options(const ConsistentFitOptions& options, int p) {
  if (!std::isfinite(options.regularization) || options.regularization < 0.0) {
    throw InputError("options.regularization", "the regularisation weight ε must be a finite number ≥ 0, got " +
                                                   short_number(options.regularization));
  }
  if (options.parameter_scale.size() != 0) {
    require_size(options.parameter_scale, p, "options.parameter_scale", "one scale per parameter, or none");
    if (!options.parameter_scale.allFinite() || !(options.parameter_scale.array() > 0.0).all()) {
      throw InputError("options.parameter_scale", "every parameter scale must be a positive finite number");
    }
  }
  if (!std::isfinite(options.projection.length_scale) || options.projection.length_scale < 0.0) {
    throw InputError("options.projection.length_scale", "the length scale must be a finite number ≥ 0 m, got " +
                                                            short_number(options.projection.length_scale));
  }
  if (!(options.projection.relative_floor > 0.0 && options.projection.relative_floor < 1.0)) {
    throw InputError("options.projection.relative_floor", "the relative eigenvalue floor must lie in (0, 1), got " +
                                                              short_number(options.projection.relative_floor));
  }
  if (options.max_iterations < 0) {
    throw InputError("options.max_iterations", "must be ≥ 0, got " + std::to_string(options.max_iterations));
  }
  const std::pair<const char*, double> tolerances[] = {{"options.gradient_tolerance", options.gradient_tolerance},
                                                        {"options.function_tolerance", options.function_tolerance},
                                                        {"options.step_tolerance", options.step_tolerance}};
  for (const auto& [field, value] : tolerances) {
    if (!std::isfinite(value) || value < 0.0) {
      throw InputError(field, "must be a finite number ≥ 0, got " + short_number(value));
    }
  }
  if (!std::isfinite(options.initial_damping) || !(options.initial_damping > 0.0)) {
    throw InputError("options.initial_damping", "must be a positive finite number, got " +
                                                    short_number(options.initial_damping));
  }
}

// E_i = ∂J/∂π_i, the pseudo-inertia of each unit vector (J is linear in π).
const std::array<Eigen::Matrix4d, 10>& pseudo_inertia_basis() {
  static const std::array<Eigen::Matrix4d, 10> basis = [] {
    std::array<Eigen::Matrix4d, 10> result;
    for (int i = 0; i < 10; ++i) result[i] = pseudo_inertia(Vector10d::Unit(i));
    return result;
  }();
  return basis;
}

// −∇²_π ln det A for one link: [tr(A⁻¹E_iA⁻¹E_j)] = [⟨W_i, W_j⟩] with W_i = L⁻¹E_iL⁻ᵀ for any
// factor A = L Lᵀ (E_i = ∂A/∂π_i = ∂J/∂π_i: the floor is constant).
Matrix10d log_det_curvature(const Eigen::Matrix4d& inverse_factor) {
  const auto& basis = pseudo_inertia_basis();
  std::array<Eigen::Matrix4d, 10> w;
  for (int i = 0; i < 10; ++i) w[i] = inverse_factor * basis[i] * inverse_factor.transpose();
  Matrix10d curvature;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j <= i; ++j) curvature(i, j) = curvature(j, i) = (w[i].array() * w[j].array()).sum();
  }
  return curvature;
}

// What link k's barrier B_k needs: the margin F_k and its centre's shifted pseudo-inertia A_c.
struct LinkBarrier {
  Eigen::Matrix4d floor;           // F_k = diag(f L², f L², f L², f): J̃ ⪰ f·I ⇔ J ⪰ F_k
  Eigen::Matrix4d inverse;         // A_c⁻¹
  double log_det = 0.0;            // ln det A_c
};

// The data after validation, reduced to at most p rows, with what every iteration needs.
struct FitData {
  int p = 0;
  Eigen::MatrixXd R;            // m'×p, m' ≤ p
  Eigen::VectorXd z;            // m'
  double offset = 0.0;          // J⊥: the cost no π can reach
  Eigen::VectorXd prior;        // π₀
  Eigen::VectorXd inv_scale;    // 1/s
  double gamma = 0.0;           // γ
  double barrier_weight = 0.0;  // μ of the current stage
  Eigen::MatrixXd gram;         // RᵀR + γS⁻²
  std::vector<int> links;       // offsets
  std::vector<LinkBarrier> barriers;
  Eigen::VectorXd lower;        // 0 for non-negative entries, −∞ for the rest
};

// One evaluated point.
struct Point {
  Eigen::VectorXd y, pi;
  std::vector<Matrix10d> jacobians;      // ∂π/∂θ per link
  std::vector<Eigen::Matrix4d> shifted;  // lower Cholesky factor of A = J − F per link
  Eigen::VectorXd data_residual;         // Rπ − z
  double data = 0.0;                     // ‖Rπ − z‖² (without J⊥)
  double prior = 0.0;                    // γ‖S⁻¹(π − π₀)‖²
  double barrier = 0.0;                  // μ Σ 2B_k
  double objective() const { return data + prior + barrier; }
  bool finite() const { return std::isfinite(data) && std::isfinite(prior) && std::isfinite(barrier); }
};

void evaluate(const FitData& d, Point& point) {
  point.pi = point.y;
  point.jacobians.resize(d.links.size());
  point.shifted.resize(d.links.size());
  for (std::size_t k = 0; k < d.links.size(); ++k) {
    point.pi.segment<10>(d.links[k]) = standard_from_log_cholesky(point.y.segment<10>(d.links[k]), &point.jacobians[k]);
  }
  point.data = point.prior = point.barrier = kInfinity;
  if (!point.pi.allFinite()) return;  // θ overflowed: an infinite cost, never multiplied on
  double barrier = 0.0;
  for (std::size_t k = 0; k < d.links.size(); ++k) {
    // A = J − F must be positive definite: that is the feasible set (J̃ ⪰ f·I, strictly).
    const Eigen::Matrix4d shifted = pseudo_inertia(point.pi.segment<10>(d.links[k])) - d.barriers[k].floor;
    const Eigen::LLT<Eigen::Matrix4d> cholesky(shifted);
    if (cholesky.info() != Eigen::Success || !(cholesky.matrixLLT().diagonal().array() > 0.0).all()) return;
    point.shifted[k] = cholesky.matrixL();
    const double log_det = 2.0 * cholesky.matrixLLT().diagonal().array().log().sum();
    barrier += 2.0 * ((d.barriers[k].inverse.array() * shifted.array()).sum() - log_det + d.barriers[k].log_det - 4.0);
  }
  point.data_residual.noalias() = d.R * point.pi;
  point.data_residual -= d.z;
  point.data = point.data_residual.squaredNorm();
  point.prior = d.gamma * (point.pi - d.prior).cwiseProduct(d.inv_scale).squaredNorm();
  point.barrier = d.barrier_weight * barrier;
}

// g = Pᵀ∇_π(½F) and H = Pᵀ ∇²_π(½F) P (block structure: O(p²·10)).
void linearise(const FitData& d, const Point& point, Eigen::VectorXd& g, Eigen::MatrixXd& curvature,
               Eigen::MatrixXd& gp, Eigen::MatrixXd& h) {
  Eigen::VectorXd w = d.R.transpose() * point.data_residual;
  w += d.gamma * (point.pi - d.prior).cwiseProduct(d.inv_scale.cwiseAbs2());
  curvature = d.gram;
  const auto& basis = pseudo_inertia_basis();
  for (std::size_t k = 0; k < d.links.size(); ++k) {
    const int offset = d.links[k];
    const Eigen::Matrix4d inverse_factor =
        point.shifted[k].triangularView<Eigen::Lower>().solve(Eigen::Matrix4d::Identity());
    const Eigen::Matrix4d inverse = inverse_factor.transpose() * inverse_factor;  // A⁻¹
    // ∂B/∂π_i = ⟨A_c⁻¹ − A⁻¹, E_i⟩; ∂²B/∂π_i∂π_j = tr(A⁻¹E_iA⁻¹E_j).
    const Eigen::Matrix4d difference = d.barriers[k].inverse - inverse;
    for (int i = 0; i < 10; ++i) w[offset + i] += d.barrier_weight * (difference.array() * basis[i].array()).sum();
    curvature.block<10, 10>(offset, offset) += d.barrier_weight * log_det_curvature(inverse_factor);
  }
  g = w;
  gp = curvature;
  for (std::size_t k = 0; k < d.links.size(); ++k) {
    const int offset = d.links[k];
    g.segment<10>(offset).noalias() = point.jacobians[k].transpose() * w.segment<10>(offset);
    gp.middleCols<10>(offset).noalias() = curvature.middleCols<10>(offset) * point.jacobians[k];
  }
  h = gp;
  for (std::size_t k = 0; k < d.links.size(); ++k) {
    const int offset = d.links[k];
    h.middleRows<10>(offset).noalias() = point.jacobians[k].transpose() * gp.middleRows<10>(offset);
  }
}

// A link's mass (kg) and length scale (m): the natural sizes of its entries are m, mL, mL².
struct LinkSize {
  double mass = 0.0, length = 0.0;
};

LinkSize size_of(const Vector10d& link) {
  const double trace_sigma = 0.5 * (link[4] + link[7] + link[9]);  // tr Σ = ½ tr I_O
  const double length = std::sqrt(trace_sigma / link[0]);
  if (link[0] > 0.0 && std::isfinite(length) && length > 0.0) return {link[0], length};
  return {};
}

// From the prior link; for a prior link with no size of its own (a placeholder), from the
// consistent link nearest the estimate, or nearest the prior itself.
LinkSize link_size(const Vector10d& prior, const Vector10d& estimate, double relative_floor) {
  LinkSize size = size_of(prior);
  if (size.mass > 0.0) return size;
  for (const Vector10d* link : {&estimate, &prior}) {
    const std::optional<LinkProjection> projection =
        detail::try_project_link(*link, detail::link_length_scale(*link), relative_floor);
    if (projection) {
      size = size_of(projection->link);
      if (size.mass > 0.0) return size;
    }
  }
  return {};
}

// The size of each link. L is options.projection.length_scale if set, else s_h/s_m of a given
// parameter scale, else the radius of gyration of the prior link about its origin.
std::vector<LinkSize> link_sizes(const ParameterStructure& structure, const ConsistentFitProblem& problem,
                                 const ConsistentFitOptions& options) {
  std::vector<LinkSize> sizes;
  for (int k = 0; k < structure.link_count(); ++k) {
    const int offset = structure.link_offsets[k];
    LinkSize size;
    if (options.parameter_scale.size() != 0) {
      size = {options.parameter_scale[offset], options.parameter_scale[offset + 1] / options.parameter_scale[offset]};
    } else {
      size = link_size(problem.prior.segment<10>(offset), problem.unconstrained.segment<10>(offset),
                       options.projection.relative_floor);
    }
    if (options.projection.length_scale > 0.0) size.length = options.projection.length_scale;
    if (!(size.length > 0.0 && std::isfinite(size.length) && size.mass > 0.0 && std::isfinite(size.mass))) {
      throw InputError("prior", structure.link_names[k] + ": neither the prior nor the estimate has a positive "
                                                          "pseudo-inertia eigenvalue, so the link has no size to "
                                                          "work with; give the prior a mass and an inertia");
    }
    sizes.push_back(size);
  }
  return sizes;
}

// The documented default of ConsistentFitOptions::parameter_scale.
Eigen::VectorXd derived_scale(const ParameterStructure& structure, const ConsistentFitProblem& problem,
                              const Eigen::MatrixXd& R, const std::vector<LinkSize>& sizes) {
  const int p = structure.parameter_count;
  Eigen::VectorXd scale = Eigen::VectorXd::Constant(p, kNaN);
  for (int k = 0; k < structure.link_count(); ++k) {
    const int offset = structure.link_offsets[k];
    const auto [mass, length] = sizes[k];
    scale[offset] = mass;
    scale.segment<3>(offset + 1).setConstant(mass * length);
    scale.segment<6>(offset + 4).setConstant(mass * length * length);
  }
  // Other entries: as visible to the data as an average link entry.
  const Eigen::VectorXd column_norms = R.colwise().norm().transpose();
  double sum = 0.0;
  int count = 0;
  for (int offset : structure.link_offsets) {
    for (int i = offset; i < offset + 10; ++i) {
      if (column_norms[i] > 0.0) {
        sum += std::pow(column_norms[i] * scale[i], 2);
        ++count;
      }
    }
  }
  const double rms = count > 0 ? std::sqrt(sum / count) : 0.0;
  for (int i = 0; i < p; ++i) {
    if (!std::isnan(scale[i])) continue;
    if (column_norms[i] > 0.0 && rms > 0.0 && std::isfinite(rms / column_norms[i])) {
      scale[i] = rms / column_norms[i];
    } else {
      const double size = std::max(std::abs(problem.prior[i]), std::abs(problem.unconstrained[i]));
      scale[i] = size > 0.0 ? size : 1.0;
    }
  }
  if (!scale.allFinite() || !(scale.array() > 0.0).all()) {
    throw InputError("prior", "the parameter scale derived from the prior is not positive and finite; pass "
                              "options.parameter_scale");
  }
  return scale;
}

// π with every link projected (L_k, the projection's floor) and every negative non-negative
// entry set to 0. A link with nothing positive to keep takes its (projected) prior.
Eigen::VectorXd make_consistent(const ParameterStructure& structure, const Eigen::VectorXd& pi,
                                const Eigen::VectorXd& prior, const std::vector<LinkSize>& sizes,
                                const ConsistentFitOptions& options, std::vector<int>* projected,
                                std::vector<int>* clipped) {
  Eigen::VectorXd result = pi;
  for (int k = 0; k < structure.link_count(); ++k) {
    const int offset = structure.link_offsets[k];
    const double length = sizes[k].length;
    std::optional<LinkProjection> projection =
        detail::try_project_link(pi.segment<10>(offset), length, options.projection.relative_floor);
    if (!projection) {
      projection = detail::try_project_link(prior.segment<10>(offset), length, options.projection.relative_floor);
      if (!projection) {
        throw InputError("prior", structure.link_names[k] +
                                      ": neither the estimate nor the prior has a positive pseudo-inertia "
                                      "eigenvalue, so there is no consistent start");
      }
      projection->changed = true;
    }
    if (projection->changed && projected) projected->push_back(k);
    result.segment<10>(offset) = projection->link;
  }
  for (int index : structure.non_negative) {
    if (result[index] < 0.0) {
      result[index] = 0.0;
      if (clipped) clipped->push_back(index);
    }
  }
  return result;
}

// Sizes, emptiness, finiteness, ranges: nothing else reaches a solver.
void check_problem(const ParameterStructure& structure, const ConsistentFitProblem& problem,
                   const ConsistentFitOptions& options) {
  check_structure(structure);
  const int p = structure.parameter_count;
  if (problem.R.rows() == 0 || problem.R.cols() != p) {
    throw InputError("R", "R must have at least one row and " + std::to_string(p) +
                              " columns (one per parameter), got " + std::to_string(problem.R.rows()) + "×" +
                              std::to_string(problem.R.cols()));
  }
  require_finite(problem.R, "R", "check the regressor for NaN or Inf samples");
  require_size(problem.z, problem.R.rows(), "z", "one per row of R");
  require_finite(problem.z, "z", "check the measured torques");
  if (!std::isfinite(problem.residual_offset) || problem.residual_offset < 0.0) {
    throw InputError("residual_offset", "the residual outside R's range must be a finite number ≥ 0, got " +
                                            short_number(problem.residual_offset));
  }
  require_size(problem.unconstrained, p, "unconstrained", "the least-squares estimate, one per parameter");
  require_finite(problem.unconstrained, "unconstrained", "the least-squares estimate");
  require_size(problem.prior, p, "prior", "one prior value per parameter");
  require_finite(problem.prior, "prior", "the prior values");
  if (problem.start.size() != 0) {
    require_size(problem.start, p, "start", "one per parameter, or none");
    require_finite(problem.start, "start", "the starting values");
  }
  validate_options(options, p);
  if (problem.R.cwiseAbs().maxCoeff() == 0.0) throw InputError("R", "R is zero: the data determine no parameter");
}

// The fit, built as Ceres's TrustRegionMinimizer is: one method per step, run in order by
// minimize() on a checked problem (check_problem()):
//
//   reduce()            R to at most p rows; the unconstrained cost
//   choose_scale()      s and γ = ε σ_max(R S)²
//   set_margins()       the prior term and each link's margin f
//   choose_start()      the projection's cost; the start and the barriers' centre
//   enter_interior()    the start in y, strictly inside the margins; the barriers; the start's costs
//   barrier_weights()   the continuation μ₀ > … > μ_last
//   run_stage()         one μ: a run of the shared minimiser (estimation/gauss_newton.h: the
//                       damping rule, the stop tests) on this object as its problem:
//     linearise()             at a new point: g, H and the free variables
//     solve()                 the damped step (damped_step())
//     candidate()             fraction_to_boundary(), the retraction through π; the model's decrease
//     evaluate_candidate()    F there
//     accept()                the candidate becomes the current point; the step's size
//   summarise()         the summary
// One object per fit: minimize() runs once (it hands the summary over).
class ConsistentFitMinimizer final : public manipid::detail::GaussNewtonProblem {
 public:
  ConsistentFitMinimizer(const ParameterStructure& structure, const ConsistentFitProblem& problem,
                         const ConsistentFitOptions& options)
      : structure_(structure), problem_(problem), options_(options), p_(structure.parameter_count) {}

  ConsistentFitSummary minimize() {
    reduce();
    choose_scale();
    set_margins();
    choose_start();
    enter_interior();
    // Intermediate stages end on any convergence rule (or on rounding) and go on to the next.
    FitTermination termination = FitTermination::max_iterations;
    const std::vector<double> weights = barrier_weights();
    damping_ = options_.initial_damping;
    for (std::size_t stage = 0; stage < weights.size(); ++stage) {
      const bool last = stage + 1 == weights.size();
      termination = run_stage(weights[stage], last);
      if (termination == FitTermination::cancelled || termination == FitTermination::max_iterations) break;
      if (!last) termination = FitTermination::max_iterations;
    }
    summarise(termination);
    return std::move(summary_);
  }

 private:
  double data_cost(const Eigen::VectorXd& pi) const { return (d_.R * pi - d_.z).squaredNorm() + d_.offset; }

  // Reduces R to at most p rows (one QR of [R | z]; the rest of z's norm joins J⊥) and prices
  // the unconstrained estimate.
  void reduce() {
    d_.p = p_;
    d_.links = structure_.link_offsets;
    d_.lower = Eigen::VectorXd::Constant(p_, -kInfinity);
    for (int index : structure_.non_negative) d_.lower[index] = 0.0;
    d_.offset = problem_.residual_offset;
    if (problem_.R.rows() > p_) {
      Eigen::MatrixXd augmented(problem_.R.rows(), p_ + 1);
      augmented << problem_.R, problem_.z;
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(augmented);
      const Eigen::MatrixXd triangle = qr.matrixQR().topRows(p_ + 1).triangularView<Eigen::Upper>();
      d_.R = triangle.topLeftCorner(p_, p_);
      d_.z = triangle.col(p_).head(p_);
      d_.offset += triangle(p_, p_) * triangle(p_, p_);
    } else {
      d_.R = problem_.R;
      d_.z = problem_.z;
    }
    summary_.unconstrained_cost = data_cost(problem_.unconstrained);
    if (!std::isfinite(summary_.unconstrained_cost)) {
      throw InputError("R", "the cost at the least-squares estimate overflows: R, z or the estimate are too large");
    }
  }

  // The parameter scale s and γ = ε σ_max(R S)².
  void choose_scale() {
    sizes_ = link_sizes(structure_, problem_, options_);
    const Eigen::VectorXd scale = options_.parameter_scale.size() != 0
                                      ? options_.parameter_scale
                                      : derived_scale(structure_, problem_, d_.R, sizes_);
    d_.inv_scale = scale.cwiseInverse();
    summary_.parameter_scale = scale;
    const Eigen::MatrixXd scaled = d_.R * scale.asDiagonal();
    const Eigen::MatrixXd scaled_gram = scaled.transpose() * scaled;
    if (!scaled_gram.allFinite()) throw InputError("R", "RᵀR overflows: R's entries are too large");
    largest_ =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scaled_gram, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
    d_.gamma = options_.regularization * largest_;
    summary_.regularization_weight = d_.gamma;
  }

  // The prior term γ‖S⁻¹(π − π₀)‖² (G = RᵀR + γS⁻²), and each link's margin f.
  void set_margins() {
    d_.prior = problem_.prior;
    d_.gram = d_.R.transpose() * d_.R;
    d_.gram.diagonal() += d_.gamma * d_.inv_scale.cwiseAbs2();
    for (int k = 0; k < structure_.link_count(); ++k) {
      const int offset = structure_.link_offsets[k];
      const double length = sizes_[k].length;
      // The margin is relative to the prior link's largest scaled eigenvalue (its projection's,
      // when the prior is not consistent: the prior term still pulls toward the values given).
      const std::optional<LinkProjection> projection =
          detail::try_project_link(problem_.prior.segment<10>(offset), length, options_.projection.relative_floor);
      if (!projection) {
        throw InputError("prior", structure_.link_names[k] + ": the prior has no positive pseudo-inertia eigenvalue; "
                                                             "give it a mass and an inertia");
      }
      if (projection->changed) summary_.inconsistent_prior_links.push_back(k);
      const Eigen::Vector4d to_scaled(1.0 / length, 1.0 / length, 1.0 / length, 1.0);
      const double largest_scaled =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(
              to_scaled.asDiagonal() * pseudo_inertia(projection->link) * to_scaled.asDiagonal(),
              Eigen::EigenvaluesOnly)
              .eigenvalues()[3];
      floors_.push_back(kFitFloorShare * options_.projection.relative_floor * largest_scaled);  // f_k, in J̃ = D J D
    }
  }

  // What projecting π_LS alone achieves (the figure the fit must not be worse than); the start,
  // `start` or the regularised least-squares point made consistent; the barriers' centre.
  void choose_start() {
    summary_.projection_cost = data_cost(
        make_consistent(structure_, problem_.unconstrained, problem_.prior, sizes_, options_, nullptr, nullptr));
    Eigen::VectorXd base = problem_.start;
    if (base.size() == 0) {
      // π_LS + G⁻¹(Rᵀ(z − Rπ_LS) + γS⁻²(π₀ − π_LS)), the minimiser of data and prior terms without
      // the constraints: π_LS along what the data determine, the prior along what they do not —
      // where the caller's π_LS is arbitrary (minimum-norm, basic) and projecting it would start
      // the fit from a degenerate link far from the answer. With γ = 0 and R rank-deficient G is
      // singular and π_LS is used as it is.
      base = problem_.unconstrained;
      const Eigen::LLT<Eigen::MatrixXd> cholesky(d_.gram);
      if (d_.gamma > 0.0 && cholesky.info() == Eigen::Success) {
        const Eigen::VectorXd correction =
            cholesky.solve(d_.R.transpose() * (d_.z - d_.R * base) +
                           d_.gamma * d_.inv_scale.cwiseAbs2().cwiseProduct(d_.prior - base));
        if (correction.allFinite()) base += correction;
      }
    }
    // The iterates start from that point made consistent at the centred start's floor (1e-2).
    // The barriers' centre: that point itself for the links it has consistent (the ordinary
    // projection leaves them alone), the start for the others (their answer lies elsewhere
    // anyway, and a centre next to the margin would make the barrier needlessly stiff).
    ConsistentFitOptions centred = options_;
    centred.projection.relative_floor = std::max(kStartFloor, options_.projection.relative_floor);
    start_ = make_consistent(structure_, base, problem_.prior, sizes_, centred, nullptr, nullptr);
    centre_ = make_consistent(structure_, base, problem_.prior, sizes_, options_, &summary_.projected_links,
                              &summary_.clipped_entries);
    for (int k : summary_.projected_links) {
      centre_.segment<10>(structure_.link_offsets[k]) = start_.segment<10>(structure_.link_offsets[k]);
    }
  }

  // The starting point in y, strictly inside the margin, the barriers, and the start's costs.
  void enter_interior() {
    current_.y = start_;
    for (int k = 0; k < structure_.link_count(); ++k) {
      const int offset = structure_.link_offsets[k];
      const double length = sizes_[k].length;
      const double floor = floors_[k];
      // The projections' floors are relative to the link's own largest eigenvalue, the margin to
      // the prior's: a link much lighter than the prior can fall below the latter. Lift its
      // spectrum by the difference (J̃ + (2f − λ_min)E) — rare, and any point inside will do.
      const Eigen::Vector4d to_scaled(1.0 / length, 1.0 / length, 1.0 / length, 1.0);
      for (Eigen::VectorXd* point : {&start_, &centre_}) {
        Eigen::Matrix4d scaled =
            to_scaled.asDiagonal() * pseudo_inertia(point->segment<10>(offset)) * to_scaled.asDiagonal();
        const double smallest =
            Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(scaled, Eigen::EigenvaluesOnly).eigenvalues()[0];
        if (smallest < 2.0 * floor) {
          scaled.diagonal().array() += 2.0 * floor - smallest;
          const Eigen::Vector4d from_scaled = to_scaled.cwiseInverse();
          point->segment<10>(offset) =
              standard_from_pseudo_inertia(from_scaled.asDiagonal() * scaled * from_scaled.asDiagonal());
        }
      }
      Vector10d theta;
      if (detail::try_log_cholesky(start_.segment<10>(offset), theta) != detail::LogCholeskyStatus::ok) {
        // Unreachable after the projection (every eigenvalue of J̃ is above the floor), kept as a guard.
        theta = log_cholesky_from_standard(start_.segment<10>(offset), "start");
      }
      current_.y.segment<10>(offset) = theta;

      // The barrier is a device of the solver, not a prior: it is centred (see above) on the
      // regularised least-squares point, which has the data's values where the data see and the
      // prior's where they do not. Where that point is consistent, the minimum is that point and
      // the barrier, having no gradient there, moves nothing; centred on the prior instead, its
      // pull (relative changes, r⁻⁴ times stiffer along a link's thin direction than the prior
      // term) would drag the directions the data cannot see away from the prior wherever the
      // data move a link, and centred on the fattened start it would pull thin links fatter.
      LinkBarrier barrier;
      barrier.floor = Eigen::Vector4d(floor * length * length, floor * length * length, floor * length * length, floor)
                          .asDiagonal();
      const Eigen::LLT<Eigen::Matrix4d> cholesky(pseudo_inertia(centre_.segment<10>(offset)) - barrier.floor);
      if (cholesky.info() != Eigen::Success) {
        throw InputError("prior",
                         structure_.link_names[k] + ": the estimate's pseudo-inertia is too close to singular");
      }
      const Eigen::Matrix4d inverse_factor = cholesky.matrixL().solve(Eigen::Matrix4d::Identity());
      barrier.inverse = inverse_factor.transpose() * inverse_factor;
      barrier.log_det = 2.0 * cholesky.matrixLLT().diagonal().array().log().sum();
      d_.barriers.push_back(barrier);
    }

    // The start's costs (the barrier weight is not set yet: it does not enter these).
    evaluate(d_, current_);
    if (!current_.finite()) {
      throw InputError("R", "the cost at the start overflows: R, z or the parameters are too large");
    }
    summary_.start = current_.pi;
    summary_.initial_cost = current_.data + d_.offset;
    z_norm_ = d_.z.norm();
  }

  // The continuation on the barrier weight μ.
  //
  // The barrier's Newton model holds only for steps short against the distance to the
  // boundary, and a thin link turns its thin axis only slowly near it: from a start far from
  // the answer, damped steps would crawl. So, as interior-point methods do, the fit follows the
  // path of minima from a larger μ₀ (further inside) down by factors of 10, each stage
  // warm-started from the last and solved loosely (relative tolerances 1e-4: looser centring
  // was seen to cost the last stage more than it saves), the last one to the requested
  // tolerances. The last weight, 0.1·γ (1e-14·σ_max(R S)² when γ = 0), leaves the barrier's
  // pull a tenth of the prior's where links are well inside: lower, the last stage only crawls
  // — its whole possible gain is about ν·μ, a few 1e-9 of the cost — in a system too
  // ill-conditioned near the margin for Cholesky (seen: 1e-4·γ took up to 900 iterations).
  //
  // μ₀ from the start's gap, as interior-point methods choose it: at the minimum for μ the
  // objective is within about ν·μ of the constrained minimum (ν = 4 per link, the barrier's
  // parameter), so μ₀ = (start's data cost − π_LS's)/ν puts the start on the path's scale — a
  // poor start (a link far outside, turned the wrong way) begins fat, where it can turn
  // cheaply, and a good one skips the stages it does not need. Capped at 1e-2·σ_max(R S)².
  std::vector<double> barrier_weights() const {
    const double last_weight = d_.gamma > 0.0 ? kLastStageShare * d_.gamma : kLastStageFloor * largest_;
    std::vector<double> weights;
    const double nu = 4.0 * static_cast<double>(d_.links.size());
    const double gap = std::max(0.0, summary_.initial_cost - summary_.unconstrained_cost);
    const double first = nu > 0.0 ? std::min(kFirstStageCap * largest_, gap / nu) : 0.0;
    for (double weight = first; weight > 1.5 * last_weight; weight *= 0.1) weights.push_back(weight);
    weights.push_back(last_weight);
    return weights;
  }

  // One stage of the continuation: Levenberg–Marquardt with bounds (projection and an active
  // set) and the π retraction at barrier weight μ, warm-started from the last stage's point and
  // damping, until a stop test holds: the requested tolerances in the last stage, kStageTolerance
  // before it.
  FitTermination run_stage(double weight, bool last) {
    d_.barrier_weight = weight;
    evaluate(d_, current_);
    GaussNewtonOptions stage;
    stage.initial_damping = std::min(damping_, options_.initial_damping);
    stage.gradient_tolerance = last ? options_.gradient_tolerance : kStageTolerance;
    stage.function_tolerance = last ? options_.function_tolerance : kStageTolerance;
    stage.step_tolerance = last ? options_.step_tolerance : kStageTolerance;
    if (last) stage.exact_fit_scale = z_norm_;  // an exact fit: a few ε of ‖z‖ is rounding
    stage.max_iterations = options_.max_iterations - summary_.iterations;
    stage.cancel = options_.cancel;
    const manipid::detail::GaussNewtonSummary run = GaussNewtonMinimizer(stage).minimize(*this);
    damping_ = run.damping;
    last_message_ = run.message;
    switch (run.stop) {
      case GaussNewtonStop::converged_exact: return FitTermination::converged_exact;
      case GaussNewtonStop::converged_gradient:
      case GaussNewtonStop::converged_noise: return FitTermination::converged_gradient;  // (no noise test here)
      case GaussNewtonStop::converged_cost: return FitTermination::converged_cost;
      case GaussNewtonStop::converged_step: return FitTermination::converged_step;
      case GaussNewtonStop::rounding_limited: return FitTermination::rounding_limited;
      case GaussNewtonStop::max_iterations: return FitTermination::max_iterations;
      case GaussNewtonStop::cancelled:
      case GaussNewtonStop::stopped: return FitTermination::cancelled;
    }
    return FitTermination::max_iterations;
  }

  // The shared minimiser's problem (estimation/gauss_newton.h). F is the stage's objective
  // ‖Rπ − z‖² + γ‖S⁻¹(π − π₀)‖² + μ Σ 2B_k (without J⊥).
  double cost() const override { return current_.objective(); }

  // g, H and the free variables: all but those on their bound that the gradient pushes outward
  // (the KKT conditions hold for those; they stay put this iteration).
  bool linearise(GaussNewtonModel& model) override {
    manipid::robot::linearise(d_, current_, g_, curvature_, gp_, h_);
    if (!g_.allFinite() || !h_.allFinite()) return false;  // never NaN into Cholesky
    free_variables_.clear();
    for (int i = 0; i < p_; ++i) {
      if (!manipid::detail::held_on_bound(current_.y[i], d_.lower[i], kInfinity, g_[i])) free_variables_.push_back(i);
    }
    model.gradient = g_;
    model.curvature_diagonal = h_.diagonal();
    model.free = free_variables_;
    return true;
  }

  bool solve(double damping, Eigen::VectorXd& step) override {
    damping_ = damping;
    std::optional<Eigen::VectorXd> solved = damped_step();
    if (!solved) return false;
    step = std::move(*solved);
    return true;
  }

  // The step cut to the boundary, its candidate point (trial_), and the model's decrease of F
  // for the step as taken, 2 × −(gᵀδ + ½ δᵀHδ); NaN when a link lands outside.
  double candidate(const Eigen::VectorXd& step) override {
    const Eigen::VectorXd cut = step * fraction_to_boundary(step);
    Eigen::VectorXd taken;
    if (!retract(cut, taken)) return std::numeric_limits<double>::quiet_NaN();
    return 2.0 * -(g_.dot(taken) + 0.5 * taken.dot(h_ * taken));
  }

  Evaluation evaluate_candidate(double& cost) override {
    evaluate(d_, trial_);
    cost = trial_.objective();
    return trial_.finite() ? Evaluation::ok : Evaluation::not_finite;
  }

  // The candidate becomes the current point; the step's size is the largest scaled move of π.
  double accept() override {
    const double moved = ((trial_.pi - current_.pi).cwiseProduct(d_.inv_scale)).cwiseAbs().maxCoeff();
    std::swap(current_, trial_);
    return moved;
  }

  void on_step(bool accepted, double damping) override {
    ++summary_.iterations;
    if (accepted) ++summary_.accepted_steps;
    damping_ = damping;
    notify(accepted);
  }

  // (H_FF + λ D_FF) δ_F = −g_F with Marquardt's D = diag(H) (so the damping is invariant to the
  // units of every variable), floored at 1e-12 of its largest so no direction is undamped; δ
  // is 0 outside F. nullopt when Cholesky fails.
  std::optional<Eigen::VectorXd> damped_step() const {
    const int n = static_cast<int>(free_variables_.size());
    const double diagonal_floor = 1e-12 * std::max(h_.diagonal().maxCoeff(), std::numeric_limits<double>::min());
    Eigen::MatrixXd system(n, n);
    Eigen::VectorXd rhs(n);
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b < n; ++b) system(a, b) = h_(free_variables_[a], free_variables_[b]);
      system(a, a) += damping_ * std::max(h_(free_variables_[a], free_variables_[a]), diagonal_floor);
      rhs[a] = -g_[free_variables_[a]];
    }
    const Eigen::LLT<Eigen::MatrixXd> cholesky(system);
    if (cholesky.info() != Eigen::Success) return std::nullopt;
    const Eigen::VectorXd solution = cholesky.solve(rhs);
    Eigen::VectorXd step = Eigen::VectorXd::Zero(p_);
    for (int a = 0; a < n; ++a) step[free_variables_[a]] = solution[a];
    return step;
  }

  // Fraction to the boundary: A_k + t ΔJ_k ≻ 0 for t < 1/λ_max(−L⁻¹ΔJ_kL⁻ᵀ) (A_k = L Lᵀ),
  // ΔJ_k the pseudo-inertia of P_k δ_k. The step goes at most 95 % of the way there.
  double fraction_to_boundary(const Eigen::VectorXd& step) const {
    double fraction = 1.0;
    for (std::size_t k = 0; k < d_.links.size(); ++k) {
      const Vector10d change = current_.jacobians[k] * step.segment<10>(d_.links[k]);
      const Eigen::Matrix4d inverse_factor =
          current_.shifted[k].triangularView<Eigen::Lower>().solve(Eigen::Matrix4d::Identity());
      const Eigen::Matrix4d toward = -(inverse_factor * pseudo_inertia(change) * inverse_factor.transpose());
      if (!toward.allFinite()) continue;  // never hand NaN to the eigensolver; the step is refused later
      const double largest_eigenvalue =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(toward, Eigen::EigenvaluesOnly).eigenvalues()[3];
      if (largest_eigenvalue > 0.0) fraction = std::min(fraction, kFractionToBoundary / largest_eigenvalue);
    }
    return fraction;
  }

  // The candidate point for `step` in trial_ (not evaluated); `taken` is the step as taken in y
  // (the bounded entries projected). False when a link lands outside.
  bool retract(const Eigen::VectorXd& step, Eigen::VectorXd& taken) {
    // The bounded entries: y + δ projected onto x ≥ 0.
    trial_.y = (current_.y + step).cwiseMax(d_.lower);
    taken = trial_.y - current_.y;
    // The links: through π. The model is Newton's in π, so the step goes to π + P_k δ_k and
    // θ is taken from there (θ_new = θ(π + P δ), which agrees with θ + δ to first order):
    // the model then describes the move exactly for the data term and to third order for
    // the barrier. The chart step θ + δ would bend away from it, by far on thin links
    // where the log-Cholesky map curves most (the fit crawls there), and a long chart step
    // can carry a link next to the boundary in one go. A point outside (only by rounding,
    // after the fraction to the boundary) has an infinite barrier and refuses the step.
    bool inside = true;
    for (std::size_t k = 0; k < d_.links.size() && inside; ++k) {
      const int offset = d_.links[k];
      const Vector10d moved = current_.pi.segment<10>(offset) + current_.jacobians[k] * step.segment<10>(offset);
      Vector10d theta;
      inside = moved.allFinite() && detail::try_log_cholesky(moved, theta) == detail::LogCholeskyStatus::ok;
      if (inside) trial_.y.segment<10>(offset) = theta;
    }
    return inside;
  }

  void notify(bool accepted) const {
    if (!options_.on_iteration) return;
    FitIteration iteration;
    iteration.iteration = summary_.iterations;
    iteration.step_accepted = accepted;
    iteration.data_cost = current_.data + d_.offset;
    iteration.regularization_cost = current_.prior;
    iteration.barrier_cost = current_.barrier;
    iteration.barrier_weight = d_.barrier_weight;
    iteration.damping = damping_;
    iteration.estimate = &current_.pi;
    options_.on_iteration(iteration);
  }

  void summarise(FitTermination termination) {
    summary_.estimate = current_.pi;
    summary_.termination = termination;
    summary_.final_cost = current_.data + d_.offset;
    summary_.regularization_cost = current_.prior;
    summary_.cost_increase = summary_.final_cost - summary_.unconstrained_cost;
    summary_.relative_cost_increase =
        summary_.unconstrained_cost > 0.0 ? summary_.cost_increase / summary_.unconstrained_cost : kNaN;
    summary_.regularization_ratio =
        summary_.final_cost > 0.0 ? summary_.regularization_cost / summary_.final_cost : kNaN;
    switch (termination) {
      case FitTermination::converged_gradient:
      case FitTermination::converged_cost:
      case FitTermination::converged_step:
      case FitTermination::rounding_limited:
        summary_.message = last_message_;  // the minimiser's words, with the last stage's (the requested) tolerances
        break;
      case FitTermination::converged_exact:
        summary_.message = "the parameters fit the data and the prior exactly, to rounding";
        break;
      case FitTermination::max_iterations:
        summary_.message = "stopped after " + std::to_string(summary_.iterations) +
                           " iterations (max_iterations) before converging; the estimate is consistent but may not "
                           "be the minimum";
        break;
      case FitTermination::cancelled:
        summary_.message = "cancelled after " + std::to_string(summary_.iterations) +
                           " iterations; the estimate is the best consistent one so far";
        break;
    }
    summary_.report = check_consistency(structure_, summary_.estimate);
  }

  const ParameterStructure& structure_;
  const ConsistentFitProblem& problem_;
  const ConsistentFitOptions& options_;
  const int p_;
  ConsistentFitSummary summary_;
  FitData d_;                        // the reduced data and what every iteration needs
  std::vector<LinkSize> sizes_;      // each link's mass and length scale
  double largest_ = 0.0;             // σ_max(R S)²
  std::vector<double> floors_;       // f_k, in J̃ = D J D (D = diag(1/L, 1/L, 1/L, 1))
  Eigen::VectorXd start_, centre_;   // π: the start, the barriers' centre
  double z_norm_ = 0.0;              // ‖z‖ (reduced), for the exact-fit test
  Point current_, trial_;
  // The iteration's state: the model at current_, its free variables, and the damping λ (the
  // minimiser's, kept across the stages).
  Eigen::VectorXd g_;
  Eigen::MatrixXd curvature_, gp_, h_;
  std::vector<int> free_variables_;
  double damping_ = 0.0;
  std::string last_message_;  // why the last stage's run stopped
};

}  // namespace

const char* to_string(FitTermination termination) {
  switch (termination) {
    case FitTermination::converged_gradient: return "converged_gradient";
    case FitTermination::converged_cost: return "converged_cost";
    case FitTermination::converged_step: return "converged_step";
    case FitTermination::converged_exact: return "converged_exact";
    case FitTermination::rounding_limited: return "rounding_limited";
    case FitTermination::max_iterations: return "max_iterations";
    case FitTermination::cancelled: return "cancelled";
  }
  return "unknown";
}

bool ConsistentFitSummary::converged() const {
  return termination != FitTermination::max_iterations && termination != FitTermination::cancelled;
}

std::string ConsistentFitSummary::brief_report() const {
  std::ostringstream text;
  text.precision(4);
  text << to_string(termination) << " after " << iterations << " iterations (" << accepted_steps
       << " accepted): cost " << initial_cost << " -> " << final_cost << ", unconstrained " << unconstrained_cost;
  if (std::isfinite(relative_cost_increase)) text << " (+" << 100.0 * relative_cost_increase << " %)";
  text << ", projection alone " << projection_cost << "; prior term " << regularization_ratio
       << " of the data term; ";
  const std::vector<int> bad = report.inconsistent_links();
  if (bad.empty()) {
    text << "every link consistent";
  } else {
    text << bad.size() << " link(s) at the edge of consistency";
  }
  return text.str();
}


ConsistentFitSummary fit_consistent(const ParameterStructure& structure, const ConsistentFitProblem& problem,
                                    const ConsistentFitOptions& options) {
  check_problem(structure, problem, options);
  return ConsistentFitMinimizer(structure, problem, options).minimize();
}

}  // namespace manipid::robot

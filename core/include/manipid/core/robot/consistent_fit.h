// consistent_fit.h — the least-squares fit of τ = Y·π over physically consistent parameters only.
//
//   minimise   ‖R π − z‖² + γ ‖S⁻¹(π − π₀)‖²
//   over       π whose every link has J̃ ⪰ f·I (J ≻ 0 with a small margin) and whose
//              non-negative entries are ≥ 0.
//
// R (m×p) and z (m) are any reduction of the stacked, filtered regression — in practice the
// triangular factor of its QR, so the cost does not grow with the number of samples. R is
// rank-deficient: the data determine only the base-parameter combinations.
//
// Prior term. Directions the data do not see stay at the prior π₀ (the URDF's CAD values).
// S = diag(s) puts every entry in its natural size (ConsistentFitOptions::parameter_scale) and
// γ = ε·σ_max(R S)², so ε weighs the prior against the data's strongest direction: along a
// direction of R S with singular value σ the estimate moves toward the prior by the fraction
// ε/(ε + (σ/σ_max)²). The default ε = 1e-8 = (1e-4)²: directions with σ/σ_max ≪ 1e-4 are the
// prior's, at σ/σ_max = 1e-3 (uncertainty.cpp's edge of "poorly determined") the prior takes
// 1 %, at 1e-2 0.01 %. The summary reports the term beside the data term.
//
// Links. Each link's ten entries are replaced by its log-Cholesky coordinates θ
// (log_cholesky.h), so every iterate has J ≻ 0. That set is open: when the data push a link
// outward (routine for slender or poorly excited links under noise) the constrained minimum
// lies on its boundary, which θ reaches only at infinity — the iterates crawl outward, never
// converge, and the link ends numerically flat (as observed without one). So the fit keeps a
// margin, J̃ ⪰ f·I in project_link()'s scaled pseudo-inertia with f a tenth of the projection's
// floor times the prior link's largest eigenvalue (the link stays at least ~3e-4 of its size
// thick), and meets it as interior-point methods do, with a barrier: the shifted log-det
// divergence (Lee, Wensing & Park, IEEE T-RO 2020)
//
//   μ·2B(J),   B = tr(A_c⁻¹A) − ln det(A_c⁻¹A) − 4,   A = J − F,  A_c = J_c − F,
//
// F the margin in J's units. B is convex in π and infinite on the margin. Its centre J_c is
// the regularised least-squares point (fit_consistent()), which has the data's values where
// the data see and the prior's where they do not: B has no gradient there, so where that
// point is consistent it is the answer and the barrier moves nothing. (For a link it has
// inconsistent, J_c is the start.) μ is followed down to 0.1·γ; where the data push a link
// against the margin, the barrier holds it off with a pull toward J_c of about a tenth of the
// prior term's — more along a slender link's thin direction, whose relative changes B weighs
// (r⁻⁴/10 of the prior term for a thickness ratio r).
//
// Non-negative entries (fv, fc, Ia) keep their own values with the bound x ≥ 0, met by
// projecting each step (an active-set projected Levenberg–Marquardt). A smooth map is worse
// exactly where it matters: with x = s², s = 0 is a stationary point of every cost, so an
// entry clipped to 0 at the start never leaves it, and near an active bound Gauss–Newton drops
// the term 2·r·∂²x/∂s² that is then the whole curvature; with x = eˢ or softplus, 0 is never
// reached and an entry whose optimum is 0 (a joint without Coulomb friction that least
// squares puts at −0.01 N·m) creeps toward it while the conditioning grows as e^{−2s}. A bound
// is what the constraint is. Free entries (friction offsets, ...) are as they are.
//
// Solver. Levenberg–Marquardt over y (θ for links, the parameter elsewhere) with the exact
// Jacobian R·∂π/∂y; its model is Newton's in π pulled back through ∂π/∂y (exact for the
// quadratic terms), with Marquardt's diagonal scaling and Eigen's Cholesky; each stage is a run
// of core's one Levenberg–Marquardt minimiser (core/src/estimation/gauss_newton.h: Nielsen's
// damping update and the stop tests). The objective depends on π only, so a link's step is taken through π,
// θ_new = θ(π + P δθ) — θ + δθ to first order — where the model is exact for the data term;
// the chart step θ + δθ would bend away from it, most on slender links. As interior-point
// methods do, a step goes at most 95 % of the way to the margin along its direction, and μ
// drops by factors of 10 from μ₀ = (start's cost − π_LS's cost)/(4 × links) (the start's gap
// over the barrier parameter, capped at 1e-2·σ_max(R S)²), each stage warm-started and the
// last solved to the requested tolerances: the barrier's Newton model holds only for steps
// short against the distance to the margin, and a slender link turns its thin axis only
// slowly near it. An iteration costs O(p²·10 + p³/3), about 0.1 ms at p = 91 whatever the
// number of samples (R is first reduced to p rows when it has more); a fit takes 10–60.
#pragma once

#include "manipid/core/robot/consistency.h"

#include <Eigen/Core>

#include <atomic>
#include <functional>
#include <string>
#include <vector>

namespace manipid::robot {

/// The data of one fit.
struct ConsistentFitProblem {
  /// R, m×p (m ≥ 1, p = structure.parameter_count), units per column: torque per unit of
  /// that parameter. Any m: when m > p it is reduced to p rows by one QR of [R | z], the
  /// rows beyond p joining `residual_offset`.
  Eigen::MatrixXd R;
  /// z, m entries, torque units (N·m for joints, after any weighting the caller applied).
  Eigen::VectorXd z;
  /// The part of the cost no π can explain (J⊥: ‖z‖² minus its projection on R's range, from
  /// the caller's QR), ≥ 0. Added to every reported cost so that relative figures mean what
  /// they say; it does not change the minimiser.
  double residual_offset = 0.0;
  /// π_LS, p: the unconstrained least-squares estimate, any one of them when R is rank-deficient
  /// (minimum-norm, basic, ...). Its cost is the comparison figure, and the start is built from it
  /// unless `start` is given (see fit_consistent()).
  Eigen::VectorXd unconstrained;
  /// π₀, p: the prior (CAD) values the prior term pulls toward. Need not be consistent (see
  /// inconsistent_prior_links), but every link needs some positive part: its size sets the
  /// margin.
  Eigen::VectorXd prior;
  /// Optional start, p (empty: built from `unconstrained`, see fit_consistent()): e.g. a
  /// previous fit, to warm-start. It is made consistent (projected, clipped) before use.
  Eigen::VectorXd start;
};

/// Why the fit stopped.
enum class FitTermination {
  converged_gradient,   ///< first-order optimality within gradient_tolerance
  converged_cost,       ///< an accepted step decreased F by less than function_tolerance·F
  converged_step,       ///< an accepted step moved no entry by more than step_tolerance of its scale
  converged_exact,      ///< the objective is zero to rounding: data and prior fit exactly
  rounding_limited,     ///< no step can decrease F any more in double precision (damping exhausted)
  max_iterations,       ///< stopped at max_iterations; the estimate is consistent but may not be optimal
  cancelled,            ///< the cancel flag was set; the estimate is the best consistent one so far
};
const char* to_string(FitTermination termination);

/// One iteration, as the progress callback sees it.
struct FitIteration {
  int iteration = 0;              ///< 1, 2, ...
  bool step_accepted = false;
  double data_cost = 0.0;         ///< ‖Rπ − z‖² + residual_offset at the current estimate
  double regularization_cost = 0.0;  ///< the prior term γ‖S⁻¹(π − π₀)‖² at the current estimate
  double barrier_cost = 0.0;         ///< the barrier term μ Σ 2B at the current estimate (the stage's μ)
  double barrier_weight = 0.0;       ///< μ of the current continuation stage
  double damping = 0.0;           ///< λ (relative to Marquardt's diagonal)
  const Eigen::VectorXd* estimate = nullptr;  ///< the current π (p); valid during the call only
};

/// Settings, with documented defaults.
struct ConsistentFitOptions {
  /// ε, the prior's weight relative to σ_max(R S)² (see the file comment). 0 switches the
  /// prior off: then a rank-deficient R leaves the null space wherever the start put it (the
  /// Gauss–Newton system is singular there; damping still solves it). Use 0 only with
  /// full-rank data.
  double regularization = 1e-8;
  /// s, p entries > 0 in the units of π: the natural size of each parameter, which makes the
  /// prior term and the step test unit-consistent. Empty = derived:
  ///  - links, from the prior link (or, when the prior link has m ≤ 0 or no extent, the
  ///    projected least-squares link, else the projected prior): s = (m, mL, mL, mL, mL², ...
  ///    mL²) with L² = tr Σ / m, its radius of gyration about the origin;
  ///  - other entries seen by the data (column j of R non-zero): ρ/‖R_j‖, with ρ the RMS of
  ///    ‖R_i‖·s_i over the link entries, i.e. as visible to the data as an average inertial
  ///    parameter; entries unseen (or with no link entries to compare): max(|π₀_j|, |π_LS_j|),
  ///    or 1 if both are 0.
  Eigen::VectorXd parameter_scale;
  /// How inconsistent links (of the start, of π_LS for projection_cost, of the prior) are
  /// made consistent, and the margin the fit keeps (a tenth of `relative_floor`); the length
  /// scale of link k is L = s_h/s_m of the parameter scale unless set here.
  ProjectionOptions projection;

  /// Stop rules of the last continuation stage (first met wins; earlier stages end at relative
  /// tolerances 1e-4 and go on to the next):
  int max_iterations = 200;            ///< iterations (accepted or not), over all stages; ~0.1 ms each at p = 91
  /// MINPACK's gtol: max over the free variables of |g_i| / (√H_ii · √F), for least squares
  /// the cosine between the residual and each Jacobian column (scale-invariant), ≤ this.
  double gradient_tolerance = 1e-10;
  /// An accepted step with (F_old − F_new) ≤ this · F_old.
  double function_tolerance = 1e-12;
  /// An accepted step with max_i |Δπ_i| / s_i ≤ this.
  double step_tolerance = 1e-10;
  /// First damping λ₀, relative to Marquardt's diagonal (Ceres's default trust region 1e4 ⇒ 1e-4).
  double initial_damping = 1e-4;

  /// Called after every iteration (from the calling thread).
  std::function<void(const FitIteration&)> on_iteration;
  /// Checked before every iteration; when it becomes true the fit stops with the best
  /// estimate so far (termination `cancelled`).
  const std::atomic<bool>* cancel = nullptr;
};

/// What happened (in the spirit of Ceres's Solver::Summary).
struct ConsistentFitSummary {
  Eigen::VectorXd estimate;   ///< π, p: every link consistent, every non-negative entry ≥ 0
  Eigen::VectorXd start;      ///< π the iterations started from (see fit_consistent())
  std::vector<int> projected_links;  ///< links (structure order) the regularised point had inconsistent, projected
  std::vector<int> clipped_entries;  ///< indices of non-negative entries it had negative, set to 0
  /// Links whose prior values are not consistent (the prior term still pulls toward them).
  std::vector<int> inconsistent_prior_links;

  FitTermination termination = FitTermination::max_iterations;
  std::string message;        ///< one sentence: why it stopped
  int iterations = 0;         ///< LM iterations made (accepted or rejected)
  int accepted_steps = 0;

  /// Data costs ‖Rπ − z‖² + residual_offset (torque² units):
  double unconstrained_cost = 0.0;  ///< at π_LS: the floor any constrained fit is compared with
  double projection_cost = 0.0;     ///< at π_LS made consistent (projected, clipped): what projecting alone achieves
  double initial_cost = 0.0;        ///< at the start the fit iterated from
  double final_cost = 0.0;          ///< at the estimate
  /// final_cost − unconstrained_cost (≥ 0 up to rounding when π_LS is a true minimiser), and
  /// that relative to unconstrained_cost (NaN when unconstrained_cost is 0: an exact fit).
  double cost_increase = 0.0;
  double relative_cost_increase = 0.0;

  double regularization_weight = 0.0;   ///< γ = ε·σ_max(R S)²
  double regularization_cost = 0.0;     ///< the prior term γ‖S⁻¹(π − π₀)‖² at the estimate
  /// regularization_cost / final_cost (NaN when final_cost is 0): the prior term's size beside
  /// the data term.
  double regularization_ratio = 0.0;
  Eigen::VectorXd parameter_scale;      ///< s used (p)

  /// The estimate's report: whether each link ended consistent (it always does: θ → π cannot
  /// leave the set, and the barrier keeps every link above the margin).
  ConsistencyReport report;

  /// Converged by one of the converged_* rules or rounding_limited.
  bool converged() const;
  /// One line: "converged_cost after 12 iterations (11 accepted): cost 1.2 -> 1.1, unconstrained
  /// 1.0 (+10 %), projection alone 1.3; prior term 1e-06 of the data term; every link consistent".
  std::string brief_report() const;
};

/// \brief The physically consistent constrained least-squares fit.
///
/// The start is `problem.start` if given, else the regularised least-squares point
///
///   π_r = π_LS + (RᵀR + γS⁻²)⁻¹(Rᵀ(z − Rπ_LS) + γS⁻²(π₀ − π_LS)),
///
/// the minimiser without the constraints: π_LS along what the data determine and the prior
/// along what they do not, where the caller's π_LS is arbitrary (minimum-norm, basic) and
/// projecting it would start from a degenerate link far from the answer. That point made
/// consistent by project_link() at the ordinary floor (a link with no positive part takes its
/// projected prior; negative non-negative entries are set to 0) is the barrier's centre; the
/// iterates start from it projected at a floor of 1e-2, a link at least about a tenth as thick
/// as it is large, rather than on the margin, where the barrier's Newton model holds only for
/// tiny steps.
///
/// Throws manipid::InputError naming the field ("R", "z", "unconstrained", "prior", "start",
/// "residual_offset", "options.regularization", ...) for wrong sizes, empty matrices,
/// non-finite entries or out-of-range options; nothing non-finite ever reaches a factorisation
/// or an eigensolver.
ConsistentFitSummary fit_consistent(const ParameterStructure& structure, const ConsistentFitProblem& problem,
                                    const ConsistentFitOptions& options = {});

}  // namespace manipid::robot

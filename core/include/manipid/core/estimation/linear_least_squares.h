// linear_least_squares.h — the one linear least-squares solve: A β ≈ y, with the rank, shrinkage and
// standard-error rules of estimation/rules.h, toward a prior where the data say little.
//
//   1. Columns scaled to unit norm (x = S β, S the column norms), so kg, kg·m and kg·m² compare; a column
//      below kNegligibleColumn of the largest is set aside — its parameter stays at the prior — because
//      scaled up it would pass for a direction of its own.
//   2. QR of the scaled rows (rows × b → b × b), then the SVD of the triangle: A_s = U diag(s) Vᵀ.
//   3. Each direction v_k of the parameters is estimated by its share f_k of the data:
//          x = x₀ + Σ_k f_k / s_k · v_k u_kᵀ (y − A_s x₀),   f_k = s_k² / (s_k² + ρ² s_1²),
//      ρ the relative ridge (0: ordinary least squares), f_k = 0 for a direction below kUnidentifiableRatio
//      of s_1 (not determined): there the estimate is the prior x₀ = S β₀. This is Tikhonov regularisation
//      toward the prior, minimising |A_s x − y|² + ρ² s_1² |x − x₀|².
//   4. Covariance per unit residual variance: S⁻¹ V diag(f_k² / s_k²) Vᵀ S⁻¹ (the estimator's, which for
//      ρ = 0 is (AᵀA)⁻¹ on the determined directions); multiply by σ² of one residual
//      (estimation/rules.h corrects σ² for low-passed residuals).
#pragma once

#include <Eigen/Core>

namespace manipid::estimation {

struct LinearSolveOptions {
  /// β₀, where directions the data do not determine stay (dim β); empty = zeros.
  Eigen::VectorXd prior;
  /// ρ ≥ 0: the relative ridge toward the prior (step 3); 0 = least squares on the determined directions.
  double ridge = 0.0;
};

struct LinearSolution {
  Eigen::VectorXd estimate;         ///< β̂
  Eigen::VectorXd scale;            ///< S: each column's norm (1 for a negligible one)
  Eigen::VectorXd singular_values;  ///< s of the scaled determining columns, largest first
  Eigen::MatrixXd directions;       ///< V: columns are directions in scaled coordinates (dim β each)
  Eigen::VectorXd data_share;       ///< f_k per direction: 1 = the data alone, 0 = the prior alone
  /// Per parameter: how much of its estimate the data determine, diag(V F Vᵀ) in scaled coordinates
  /// (1: the data alone; 0: the prior alone — a negligible column or a direction not determined).
  Eigen::VectorXd parameter_share;
  Eigen::VectorXi negligible;       ///< 1 for a column set aside in step 1
  int determined = 0;               ///< directions at or above kUnidentifiableRatio
  double condition_number = 0.0;    ///< s_1 / s_min (∞ when a direction is not determined or a column negligible)
  Eigen::MatrixXd covariance_unit;  ///< step 4, dim β × dim β
  Eigen::VectorXd residual;         ///< y − A β̂
};

/// Solves A β ≈ y (see the file comment). A: rows × b with rows ≥ 1; y: rows. Throws InputError("rows")
/// for mismatched sizes, InputError("prior") for a prior of the wrong size or not finite,
/// InputError("ridge") for ρ < 0.
LinearSolution solve_linear(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::VectorXd>& y,
                            const LinearSolveOptions& options = {});

}  // namespace manipid::estimation

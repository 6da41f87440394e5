// linear_least_squares_test.cpp — the one linear solve: exact fits, the rank rule, negligible columns, the ridge
// toward the prior against its closed form, and the covariance.
#include "manipid/core/estimation/linear_least_squares.h"

#include "../input_error_field.h"
#include "manipid/core/estimation/rules.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace manipid::estimation {
namespace {

Eigen::MatrixXd random_matrix(int rows, int cols, std::mt19937_64& engine) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(rows, cols);
  for (int c = 0; c < cols; ++c) {
    for (int r = 0; r < rows; ++r) A(r, c) = normal(engine);
  }
  return A;
}

TEST(LinearLeastSquares, RecoversAnExactFitWhateverTheColumnsUnits) {
  std::mt19937_64 engine(1);
  Eigen::MatrixXd A = random_matrix(200, 6, engine);
  A.col(2) *= 1e2;   // kg·m² against kg: the scaling makes them alike (10^-4 apart, above kNegligibleColumn)
  A.col(4) *= 1e-2;
  Eigen::VectorXd beta(6);
  beta << 1.0, -2.0, 3e-4, 0.5, 700.0, -0.25;
  const LinearSolution solution = solve_linear(A, A * beta);
  EXPECT_LT((solution.estimate - beta).cwiseQuotient(beta).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(solution.residual.norm(), 1e-9);
  EXPECT_EQ(solution.determined, 6);
  EXPECT_TRUE(std::isfinite(solution.condition_number));
  EXPECT_LT((solution.parameter_share.array() - 1.0).abs().maxCoeff(), 1e-12);
}

TEST(LinearLeastSquares, ADirectionTheDataDoNotSeeStaysAtThePrior) {
  // Columns 1 and 2 equal: only β1 + β2 is determined; β1 − β2 keeps the prior's value.
  std::mt19937_64 engine(2);
  Eigen::MatrixXd A = random_matrix(100, 3, engine);
  A.col(2) = A.col(1);
  Eigen::VectorXd beta(3), prior(3);
  beta << 1.0, 2.0, 3.0;
  prior << 0.0, 10.0, 4.0;
  LinearSolveOptions options;
  options.prior = prior;
  const LinearSolution solution = solve_linear(A, A * beta, options);
  EXPECT_EQ(solution.determined, 2);
  EXPECT_TRUE(std::isinf(solution.condition_number));
  EXPECT_NEAR(solution.estimate[0], 1.0, 1e-12);
  EXPECT_NEAR(solution.estimate[1] + solution.estimate[2], 5.0, 1e-12);
  EXPECT_NEAR(solution.estimate[1] - solution.estimate[2], prior[1] - prior[2], 1e-12);
  EXPECT_NEAR(solution.parameter_share[1], 0.5, 1e-12);
  EXPECT_NEAR(solution.parameter_share[0], 1.0, 1e-12);
}

TEST(LinearLeastSquares, ANegligibleColumnIsSetAsideAtThePrior) {
  // A column below kNegligibleColumn of the largest (a rounded URDF angle's residue): scaled up, it would be
  // fitted as a direction of its own; it stays at the prior with no share of the data.
  std::mt19937_64 engine(3);
  Eigen::MatrixXd A = random_matrix(100, 3, engine);
  A.col(1) *= 0.1 * kNegligibleColumn;
  Eigen::VectorXd beta(3), prior(3);
  beta << 1.0, 5e4, -2.0;
  prior << 0.0, 7.0, 0.0;
  LinearSolveOptions options;
  options.prior = prior;
  const LinearSolution solution = solve_linear(A, A * beta, options);
  EXPECT_EQ(solution.negligible[1], 1);
  EXPECT_EQ(solution.estimate[1], 7.0);
  EXPECT_EQ(solution.parameter_share[1], 0.0);
  EXPECT_TRUE(std::isinf(solution.condition_number));
  // The others explain what the prior's column does not: with it at 7 instead of 5e4, β0 and β2 absorb the
  // difference as well as they can (least squares on the rest).
  const Eigen::VectorXd rest = A * beta - A.col(1) * 7.0;
  Eigen::MatrixXd B(100, 2);
  B << A.col(0), A.col(2);
  const Eigen::VectorXd expected = (B.transpose() * B).ldlt().solve(B.transpose() * rest);
  EXPECT_NEAR(solution.estimate[0], expected[0], 1e-12);
  EXPECT_NEAR(solution.estimate[2], expected[1], 1e-12);
}

TEST(LinearLeastSquares, TheRidgeIsTikhonovTowardThePriorInScaledCoordinates) {
  std::mt19937_64 engine(4);
  const Eigen::MatrixXd A = random_matrix(80, 5, engine);
  const Eigen::VectorXd y = random_matrix(80, 1, engine).col(0);
  Eigen::VectorXd prior(5);
  prior << 1.0, -1.0, 0.5, 2.0, 0.0;
  LinearSolveOptions options;
  options.prior = prior;
  options.ridge = 0.3;
  const LinearSolution solution = solve_linear(A, y, options);
  // minimise |A_s x − y|² + ρ² s₁² |x − x₀|², x = S β.
  const Eigen::VectorXd scale = A.colwise().norm().transpose();
  const Eigen::MatrixXd As = A * scale.cwiseInverse().asDiagonal();
  const double s1 = Eigen::JacobiSVD<Eigen::MatrixXd>(As).singularValues()[0];
  const double weight = 0.3 * 0.3 * s1 * s1;
  const Eigen::VectorXd x0 = scale.cwiseProduct(prior);
  const Eigen::MatrixXd normal = As.transpose() * As + weight * Eigen::MatrixXd::Identity(5, 5);
  const Eigen::VectorXd x = normal.ldlt().solve(As.transpose() * y + weight * x0);
  EXPECT_LT((solution.estimate - x.cwiseQuotient(scale)).norm(), 1e-12 * x.norm());
  EXPECT_GT(solution.parameter_share.minCoeff(), 0.0);
  EXPECT_LT(solution.parameter_share.maxCoeff(), 1.0);
}

TEST(LinearLeastSquares, TheCovarianceIsTheInverseGramMatrixWithoutRidge) {
  std::mt19937_64 engine(5);
  Eigen::MatrixXd A = random_matrix(60, 4, engine);
  A.col(3) *= 50.0;
  const LinearSolution solution = solve_linear(A, random_matrix(60, 1, engine).col(0));
  const Eigen::MatrixXd inverse = (A.transpose() * A).inverse();
  EXPECT_LT((solution.covariance_unit - inverse).norm(), 1e-10 * inverse.norm());
}

TEST(LinearLeastSquares, RefusesWhatItCannotSolve) {
  const auto field_of = [](auto&& call) { return testing::input_error_field(call); };
  const Eigen::MatrixXd A = Eigen::MatrixXd::Identity(3, 2);
  EXPECT_EQ(field_of([&] { solve_linear(A, Eigen::VectorXd::Ones(2)); }), "rows");
  LinearSolveOptions options;
  options.prior = Eigen::VectorXd::Ones(3);
  EXPECT_EQ(field_of([&] { solve_linear(A, Eigen::VectorXd::Ones(3), options); }), "prior");
  options.prior = Eigen::VectorXd();
  options.ridge = -1.0;
  EXPECT_EQ(field_of([&] { solve_linear(A, Eigen::VectorXd::Ones(3), options); }), "ridge");
}

}  // namespace
}  // namespace manipid::estimation

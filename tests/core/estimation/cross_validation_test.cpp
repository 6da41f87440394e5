// cross_validation_test.cpp — blocked folds over time: bins, guards, and held-out errors equal to fitting each
// fold's training rows with the one linear solve and scoring its test rows by hand.
#include "manipid/core/estimation/cross_validation.h"

#include "manipid/core/estimation/linear_least_squares.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace manipid::estimation {
namespace {

TEST(CrossValidation, BinsCutEachRunIntoFoldsAndGuardsTheirNeighbours) {
  const TimeBins bins({{0.0, 10.0}, {0.0, 5.0}}, 5, 2);  // 10 bins a run: 1 s and 0.5 s wide
  EXPECT_EQ(bins.count(), 20);
  EXPECT_EQ(bins.bin(0, 0.0), 0);
  EXPECT_EQ(bins.bin(0, 9.99), 9);
  EXPECT_EQ(bins.bin(0, 10.0), 9);
  EXPECT_EQ(bins.bin(1, 2.6), 10 + 5);
  EXPECT_EQ(bins.bin(1, 5.5), -1);
  EXPECT_EQ(bins.test_bins(1), (std::vector<int>{2, 3, 12, 13}));
  // Fold 1 tests 2..4 s of run 0: with a 0.5 s guard its training leaves out bins 1 and 4 (1..2 s, 4..5 s)
  // of run 0, and of run 1 (1..2 s tested) bins within 0.5 s: 0.5..1 s and 2..2.5 s.
  const std::vector<int> train = bins.train_bins(1, 0.5);
  for (int excluded : {1, 2, 3, 4, 11, 12, 13, 14}) EXPECT_EQ(std::count(train.begin(), train.end(), excluded), 0) << excluded;
  for (int included : {0, 5, 9, 10, 15, 19}) EXPECT_EQ(std::count(train.begin(), train.end(), included), 1) << included;
}

TEST(CrossValidation, RowsGiveTheirRunsSpansAndTheirBins) {
  // Rows of two runs, out of order: each run's span is its first and last row time; each row's bin is the
  // bin its run and time fall in.
  const std::vector<int> run_of_row = {1, 0, 0, 1, 0};
  const std::vector<double> time_of_row = {2.0, 0.5, 10.5, 7.0, 3.0};
  const std::vector<std::pair<double, double>> spans = run_spans(run_of_row, time_of_row, 2);
  EXPECT_EQ(spans, (std::vector<std::pair<double, double>>{{0.5, 10.5}, {2.0, 7.0}}));
  const TimeBins bins(spans, 5, 2);  // run 0: 1 s bins from 0.5 s; run 1: 0.5 s bins from 2 s
  EXPECT_EQ(bins_of_rows(bins, run_of_row, time_of_row), (std::vector<int>{10, 0, 9, 19, 2}));
}

TEST(CrossValidation, HeldOutErrorsAreThoseOfFittingEachFoldByHand) {
  std::mt19937_64 engine(7);
  std::normal_distribution<double> normal;
  const int rows = 400, p = 4;
  Eigen::MatrixXd A(rows, p);
  Eigen::VectorXd beta(p), time(rows);
  beta << 1.0, -0.5, 2.0, 0.1;
  for (int r = 0; r < rows; ++r) {
    time[r] = 0.01 * r;
    for (int c = 0; c < p; ++c) A(r, c) = normal(engine) * (c + 1);
  }
  const Eigen::VectorXd y = A * beta + 0.3 * Eigen::VectorXd::NullaryExpr(rows, [&] { return normal(engine); });
  const TimeBins bins({{0.0, time[rows - 1]}}, 4, 3);
  std::vector<int> bin_of_row(rows);
  for (int r = 0; r < rows; ++r) bin_of_row[static_cast<std::size_t>(r)] = bins.bin(0, time[r]);
  const BinnedSums sums = bin_rows(A, y, bin_of_row, bins.count());
  const Eigen::VectorXd prior = Eigen::VectorXd::Zero(p);
  const std::vector<int> columns{0, 1, 2, 3};
  const double guard = 0.2;
  const CrossValidation cv = cross_validate(sums, sums, bins, guard, columns, prior, {0.0, 0.05});
  for (int which = 0; which < 2; ++which) {
    double error = 0.0;
    for (int fold = 0; fold < 4; ++fold) {
      const std::vector<int> train = bins.train_bins(fold, guard), test = bins.test_bins(fold);
      std::vector<Eigen::Index> train_rows, test_rows;
      for (int r = 0; r < rows; ++r) {
        const int b = bin_of_row[static_cast<std::size_t>(r)];
        if (std::count(train.begin(), train.end(), b)) train_rows.push_back(r);
        if (std::count(test.begin(), test.end(), b)) test_rows.push_back(r);
      }
      // The training rows' own column scales differ from all rows': compare at ridge 0 only where scaling
      // does not matter, and at ρ > 0 through the scaled closed form with the all-rows scales.
      const Eigen::MatrixXd At = A(train_rows, Eigen::all);
      Eigen::VectorXd fitted;
      if (which == 0) {
        fitted = solve_linear(At, y(train_rows)).estimate;
      } else {
        const Eigen::VectorXd scale = A.colwise().norm().transpose();
        const Eigen::MatrixXd As = At * scale.cwiseInverse().asDiagonal();
        const Eigen::MatrixXd G = As.transpose() * As;
        const double top = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(G).eigenvalues().maxCoeff();
        const Eigen::VectorXd x =
            (G + 0.05 * 0.05 * top * Eigen::MatrixXd::Identity(p, p)).ldlt().solve(As.transpose() * y(train_rows));
        fitted = x.cwiseQuotient(scale);
      }
      error += (A(test_rows, Eigen::all) * fitted - y(test_rows)).squaredNorm();
    }
    EXPECT_NEAR(cv.squared_error[which], error, 1e-9 * error) << (which ? "ridge 0.05" : "ridge 0");
  }
  EXPECT_NEAR(cv.target_energy, y.squaredNorm(), 1e-9 * y.squaredNorm());  // every row is tested once
  EXPECT_EQ(cv.best, cv.squared_error[0] <= cv.squared_error[1] ? 0 : 1);
}

}  // namespace
}  // namespace manipid::estimation

// uncertainty_test.cpp — the paper's standard errors and identifiability from an information matrix, unit by
// unit: the covariance of a well-posed problem, a direction the data cannot see, a barely seen one, non-finite
// input (paper/uncertainty.h, internal to core).
#include "paper/uncertainty.h"

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <cmath>

namespace manipid::detail {
namespace {

UncertaintyInput input(const Eigen::VectorXd& theta, const Eigen::MatrixXd& information, double variance) {
  UncertaintyInput in;
  for (Eigen::Index i = 0; i < theta.size(); ++i) in.names.push_back("p" + std::to_string(i + 1));
  in.theta = theta;
  in.free.assign(static_cast<std::size_t>(theta.size()), true);
  in.information = information;
  in.residual_variance = variance;
  return in;
}

TEST(Uncertainty, AWellPosedProblemHasTheInverseInformationAsCovariance) {
  Eigen::VectorXd theta(3);
  theta << 2.0, -0.5, 30.0;
  Eigen::MatrixXd J(5, 3);
  J << 1, 0.2, 0.01, 0.3, 2, 0.02, 0.1, 0.1, 0.5, 2, 0, 0.1, 0, 1, 0.3;
  const Eigen::MatrixXd H = J.transpose() * J;
  const Uncertainty result = assess_uncertainty(input(theta, H, 0.04));
  const Eigen::MatrixXd covariance = 0.04 * H.inverse();
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(result.std_errors[i], std::sqrt(covariance(i, i)), 1e-12 * std::sqrt(covariance(i, i)));
  EXPECT_NEAR(result.correlation(0, 1), covariance(0, 1) / std::sqrt(covariance(0, 0) * covariance(1, 1)), 1e-12);
  EXPECT_TRUE(result.report.all_identifiable());
  EXPECT_TRUE(result.report.findings.empty());
  EXPECT_TRUE(result.unavailable.empty());
}

TEST(Uncertainty, ADirectionTheDataCannotSeeNamesItsParametersAndLeavesTheOthers) {
  // p1 and p2 enter only as their sum (equal columns); p3 alone.
  Eigen::VectorXd theta(3);
  theta << 1.0, 1.0, 4.0;
  Eigen::MatrixXd J(4, 3);
  J << 1, 1, 0.2, 2, 2, 0.1, 0.5, 0.5, 1, 1, 1, 3;
  const Uncertainty result = assess_uncertainty(input(theta, J.transpose() * J, 1.0));
  EXPECT_EQ(result.report.unidentifiable, (std::vector<std::string>{"p1", "p2"}));
  EXPECT_TRUE(std::isnan(result.std_errors[0]));
  EXPECT_TRUE(std::isnan(result.std_errors[1]));
  EXPECT_TRUE(std::isfinite(result.std_errors[2]));
  ASSERT_FALSE(result.report.findings.empty());
  EXPECT_NE(result.report.findings.back().find("the data cannot determine p1 and p2"), std::string::npos)
      << result.report.findings.back();
}

TEST(Uncertainty, ABarelySeenDirectionIsAFindingNotAnUnidentifiableParameter) {
  // Columns 1e-4 apart in relative terms: above the unidentifiable ratio (1e-6), below the weak one (1e-3).
  Eigen::VectorXd theta(2);
  theta << 1.0, 1.0;
  Eigen::MatrixXd J(3, 2);
  J << 1, 1, 2, 2 + 2e-4, 1, 1 - 1e-4;
  const Uncertainty result = assess_uncertainty(input(theta, J.transpose() * J, 1e-12));
  EXPECT_TRUE(result.report.all_identifiable());
  ASSERT_EQ(result.report.findings.size(), 1u);
  EXPECT_NE(result.report.findings[0].find("the data barely separate p1 and p2"), std::string::npos) << result.report.findings[0];
}

TEST(Uncertainty, NonFiniteInputIsNotAssessedAndSaysWhy) {
  Eigen::VectorXd theta(2);
  theta << 1.0, std::nan("");
  const Uncertainty result = assess_uncertainty(input(theta, Eigen::MatrixXd::Identity(2, 2), 1.0));
  EXPECT_EQ(result.unavailable, "the estimate is not a finite number");
  EXPECT_TRUE(std::isnan(result.std_errors[0]));
}

}  // namespace
}  // namespace manipid::detail

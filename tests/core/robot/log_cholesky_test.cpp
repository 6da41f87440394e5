// log_cholesky_test.cpp — θ ↔ π round trips, every θ consistent, the header's formulas, the Jacobian.
#include "manipid/core/robot/log_cholesky.h"

#include "manipid/core/errors.h"
#include "rigid_bodies.h"

#include <gtest/gtest.h>

#include <cmath>

namespace manipid::robot {
namespace {

using testing::box_inertia;
using testing::place;
using testing::random_log_cholesky;
using testing::some_rotation;

TEST(LogCholesky, BoxAtItsCentreHasKnownCoordinates) {
  // m = e^{2α}; t = c = 0; S Sᵀ = Σ_c/m = diag(a², b², c²)/12, so e^{d_i} = edge/√12 and s = 0.
  const double m = 3.0, a = 0.4, b = 0.2, c = 0.1;
  const LogCholesky theta = log_cholesky_from_standard(place(m, box_inertia(m, a, b, c), Eigen::Vector3d::Zero()));
  LogCholesky expected;
  expected << 0.5 * std::log(m), std::log(a / std::sqrt(12.0)), std::log(b / std::sqrt(12.0)),
      std::log(c / std::sqrt(12.0)), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0;
  EXPECT_LT((theta - expected).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(LogCholesky, CentreOfMassIsT) {
  const Eigen::Vector3d com(0.3, -0.1, 0.25);
  const LogCholesky theta =
      log_cholesky_from_standard(place(2.0, box_inertia(2.0, 0.3, 0.2, 0.1), com, some_rotation()));
  EXPECT_LT((theta.tail<3>() - com).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_NEAR(theta[0], 0.5 * std::log(2.0), 1e-15);
}

TEST(LogCholesky, RoundTripThetaToStandardToTheta) {
  std::mt19937_64 engine(1);
  for (int trial = 0; trial < 1000; ++trial) {
    const LogCholesky theta = random_log_cholesky(engine);
    const LogCholesky back = log_cholesky_from_standard(standard_from_log_cholesky(theta));
    EXPECT_LT((back - theta).cwiseAbs().maxCoeff(), 1e-12) << theta.transpose();
  }
}

TEST(LogCholesky, RoundTripStandardToThetaToStandard) {
  std::mt19937_64 engine(2);
  for (int trial = 0; trial < 200; ++trial) {
    const Vector10d link = standard_from_log_cholesky(random_log_cholesky(engine));
    const Vector10d back = standard_from_log_cholesky(log_cholesky_from_standard(link));
    EXPECT_LT((back - link).cwiseAbs().maxCoeff(), 1e-12 * link.cwiseAbs().maxCoeff());
  }
}

TEST(LogCholesky, EveryThetaGivesAConsistentLink) {
  // Well beyond the range of any link: masses e^{±8} kg, conditional radii of gyration
  // e^{-4}..e^{1} m (18 mm to 2.7 m), couplings ±0.5 m, offsets ±2 m. Far thinner bodies are
  // consistent too, mathematically, but their thickness falls below what double precision
  // resolves next to their size, and check_link then rightly calls them flat.
  std::mt19937_64 engine(3);
  std::uniform_real_distribution<double> alpha(-4.0, 4.0), d(-4.0, 1.0), s(-0.5, 0.5), t(-2.0, 2.0);
  for (int trial = 0; trial < 2000; ++trial) {
    LogCholesky theta;
    theta << alpha(engine), d(engine), d(engine), d(engine), s(engine), s(engine), s(engine), t(engine), t(engine),
        t(engine);
    std::vector<std::string> findings;
    const LinkConsistency result = check_link(standard_from_log_cholesky(theta), "random", &findings);
    ASSERT_TRUE(result.consistent()) << theta.transpose() << "\n" << (findings.empty() ? "" : findings.front());
  }
}

TEST(LogCholesky, MatchesTheFormulasWrittenInTheHeader) {
  std::mt19937_64 engine(4);
  for (int trial = 0; trial < 50; ++trial) {
    const LogCholesky theta = random_log_cholesky(engine);
    const double alpha = theta[0], e1 = std::exp(theta[1]), e2 = std::exp(theta[2]), e3 = std::exp(theta[3]);
    const double s12 = theta[4], s23 = theta[5], s13 = theta[6], t1 = theta[7], t2 = theta[8], t3 = theta[9];
    const double S11 = e1 * e1 + s12 * s12 + s13 * s13 + t1 * t1;
    const double S22 = e2 * e2 + s23 * s23 + t2 * t2;
    const double S33 = e3 * e3 + t3 * t3;
    const double S12 = s12 * e2 + s13 * s23 + t1 * t2;
    const double S13 = s13 * e3 + t1 * t3;
    const double S23 = s23 * e3 + t2 * t3;
    Vector10d expected;
    expected << 1.0, t1, t2, t3, S22 + S33, -S12, -S13, S11 + S33, -S23, S11 + S22;
    expected *= std::exp(2.0 * alpha);
    const Vector10d link = standard_from_log_cholesky(theta);
    EXPECT_LT((link - expected).cwiseAbs().maxCoeff(), 1e-14 * expected.cwiseAbs().maxCoeff());
  }
}

TEST(LogCholesky, JacobianMatchesCentralDifferences) {
  std::mt19937_64 engine(5);
  for (int trial = 0; trial < 100; ++trial) {
    const LogCholesky theta = random_log_cholesky(engine);
    Matrix10d jacobian;
    standard_from_log_cholesky(theta, &jacobian);
    // Central differences: truncation h²/6·π''' ≈ 1e-12 relative, rounding ε/h ≈ 2e-11.
    const double h = 1e-5;
    Matrix10d numeric;
    for (int j = 0; j < 10; ++j) {
      LogCholesky plus = theta, minus = theta;
      plus[j] += h;
      minus[j] -= h;
      numeric.col(j) = (standard_from_log_cholesky(plus) - standard_from_log_cholesky(minus)) / (2.0 * h);
    }
    EXPECT_LT((jacobian - numeric).norm(), 1e-7 * jacobian.norm()) << "theta " << theta.transpose();
    // Column by column too, so no small column hides behind a big one.
    for (int j = 0; j < 10; ++j) {
      EXPECT_LT((jacobian.col(j) - numeric.col(j)).norm(), 1e-7 * jacobian.col(j).norm() + 1e-12 * jacobian.norm())
          << "column " << j;
    }
  }
}

TEST(LogCholesky, JacobianIsInvertible) {
  // θ → π is a diffeomorphism onto the consistent set: the Gauss–Newton matrix of the fit
  // stays regular wherever R sees the link.
  std::mt19937_64 engine(6);
  for (int trial = 0; trial < 100; ++trial) {
    Matrix10d jacobian;
    standard_from_log_cholesky(random_log_cholesky(engine), &jacobian);
    EXPECT_GT(std::abs(jacobian.determinant()), 0.0);
    EXPECT_TRUE(jacobian.fullPivLu().isInvertible());
  }
}

TEST(LogCholesky, InconsistentLinkHasNoCoordinates) {
  Vector10d link = place(1.0, Eigen::Vector3d(3.0, 1.0, 1.0).asDiagonal(), Eigen::Vector3d::Zero());
  try {
    log_cholesky_from_standard(link, "link4");
    FAIL() << "expected an InputError";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "link4");
    EXPECT_NE(std::string(error.what()).find("not positive definite"), std::string::npos) << error.what();
  }
  link[0] = 0.0;
  EXPECT_THROW(log_cholesky_from_standard(link), InputError);
  link[0] = std::nan("");
  EXPECT_THROW(log_cholesky_from_standard(link), InputError);
}

}  // namespace
}  // namespace manipid::robot

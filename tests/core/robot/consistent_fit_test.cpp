// consistent_fit_test.cpp — the constrained fit: exact recovery, repair, the null space, bounds, cancel, bad input.
#include "manipid/core/robot/consistent_fit.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/log_cholesky.h"
#include "rigid_bodies.h"
#include "../input_error_expectations.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

namespace manipid::robot {
namespace {

using test_support::field_of;

using testing::arm_structure;
using testing::random_log_cholesky;

// A robot's worth of parameters: truth, a prior near it (CAD values are never exact), and the
// physical scale s of each entry (the documented default: m, mL, mL² from the prior link; |prior|
// for friction here).
struct Case {
  ParameterStructure structure;
  Eigen::VectorXd truth, prior, scale;
};

Case make_case(int links, std::mt19937_64& engine) {
  Case c;
  c.structure = arm_structure(links);
  const int p = c.structure.parameter_count;
  c.truth.resize(p);
  c.prior.resize(p);
  c.scale.resize(p);
  std::normal_distribution<double> nudge(0.0, 0.05);
  std::uniform_real_distribution<double> viscous(0.1, 2.0), coulomb(0.1, 3.0), offset(-0.5, 0.5);
  for (int k = 0; k < links; ++k) {
    const LogCholesky theta = random_log_cholesky(engine);
    LogCholesky near = theta;
    for (int i = 0; i < 10; ++i) near[i] += nudge(engine);
    c.truth.segment<10>(10 * k) = standard_from_log_cholesky(theta);
    const Vector10d prior = standard_from_log_cholesky(near);
    c.prior.segment<10>(10 * k) = prior;
    const double length = std::sqrt(0.5 * (prior[4] + prior[7] + prior[9]) / prior[0]);
    c.scale.segment<10>(10 * k) << prior[0], Eigen::Vector3d::Constant(prior[0] * length),
        Eigen::Matrix<double, 6, 1>::Constant(prior[0] * length * length);
  }
  for (int k = 0; k < links; ++k) {
    const int base = 10 * links + 3 * k;
    c.truth.segment<3>(base) << viscous(engine), coulomb(engine), offset(engine);
    for (int i = 0; i < 3; ++i) c.prior[base + i] = c.truth[base + i] * (1.0 + 4.0 * nudge(engine));
    c.scale.segment<3>(base) = c.prior.segment<3>(base).cwiseAbs();
  }
  return c;
}

// A random regressor whose columns see every parameter at its own scale: R = A·S⁻¹.
Eigen::MatrixXd random_regressor(int rows, const Eigen::VectorXd& scale, std::mt19937_64& engine) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd a(rows, scale.size());
  for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = normal(engine);
  return a * scale.cwiseInverse().asDiagonal();
}

double scaled_error(const Eigen::VectorXd& estimate, const Eigen::VectorXd& truth, const Eigen::VectorXd& scale) {
  return (estimate - truth).cwiseQuotient(scale).cwiseAbs().maxCoeff();
}

TEST(ConsistentFit, FullRankDataGiveTheTruthBack) {
  std::mt19937_64 engine(21);
  const Case c = make_case(3, engine);
  const int p = c.structure.parameter_count;
  ConsistentFitProblem problem;
  problem.R = random_regressor(2 * p, c.scale, engine);
  problem.z = problem.R * c.truth;
  problem.unconstrained = c.truth;  // the least-squares solution of noise-free data
  problem.prior = c.prior;
  problem.start = c.prior;          // start far from the answer, so the solver has to find it
  ConsistentFitOptions options;
  options.regularization = 0.0;     // full rank: no prior needed, and none to bias the answer
  const ConsistentFitSummary summary = fit_consistent(c.structure, problem, options);
  EXPECT_TRUE(summary.converged()) << summary.brief_report();
  EXPECT_LT(scaled_error(summary.estimate, c.truth, c.scale), 1e-8) << summary.brief_report();
  EXPECT_LT((summary.estimate - c.truth).cwiseAbs().maxCoeff(), 1e-8 * c.truth.cwiseAbs().maxCoeff());
  // The data are exact: both costs are rounding, ~1e-30 of ‖z‖².
  EXPECT_LT(summary.unconstrained_cost, 1e-24 * problem.z.squaredNorm());
  EXPECT_LT(summary.final_cost, 1e-20 * problem.z.squaredNorm());
  EXPECT_LT(std::abs(summary.cost_increase), 1e-20 * problem.z.squaredNorm());
  EXPECT_GT(summary.initial_cost, 1e-4 * problem.z.squaredNorm());  // it did start far away
  EXPECT_TRUE(summary.report.consistent());

  // With the default prior weight the estimate moves toward the prior by about ε·κ² of their
  // distance (κ = cond(R S) ≈ 6 here), more along the thin directions of thin links where the
  // margin's barrier adds its pull (r⁻⁴/10 times the prior's for thickness ratio r; these
  // random links go down to r ≈ 0.1): 8e-5 of the distance here, 1e-3 is the bound.
  const ConsistentFitSummary regularised = fit_consistent(c.structure, problem);
  EXPECT_TRUE(regularised.converged()) << regularised.brief_report();
  EXPECT_LT(scaled_error(regularised.estimate, c.truth, c.scale), 1e-3 * scaled_error(c.prior, c.truth, c.scale));
  EXPECT_GT(regularised.regularization_weight, 0.0);
}

// A thin link (one radius of gyration 1e-3 m) and a joint without Coulomb friction, seen by
// three times as many rows as parameters with 1 % noise: the least-squares estimate is
// inconsistent, as on real arms (thin or poorly excited links come out with indefinite inertias).
struct NoisyCase {
  Case c;
  ConsistentFitProblem problem;
};

NoisyCase noisy_case(std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  NoisyCase n;
  n.c = make_case(3, engine);
  LogCholesky thin;
  thin << 0.5 * std::log(2.0), std::log(0.15), std::log(0.05), std::log(1e-3), 0.01, -0.02, 0.0, 0.2, 0.0, 0.05;
  n.c.truth.segment<10>(10) = standard_from_log_cholesky(thin);
  n.c.truth[31] = 0.0;  // fc of joint 1
  const int p = n.c.structure.parameter_count;
  n.problem.R = random_regressor(3 * p, n.c.scale, engine);
  const Eigen::VectorXd clean = n.problem.R * n.c.truth;
  std::normal_distribution<double> normal(0.0, 1.0);
  n.problem.z = clean;
  const double sigma = 0.01 * clean.norm() / std::sqrt(double(clean.size()));
  for (Eigen::Index i = 0; i < n.problem.z.size(); ++i) n.problem.z[i] += sigma * normal(engine);
  n.problem.unconstrained = n.problem.R.colPivHouseholderQr().solve(n.problem.z);
  n.problem.prior = n.c.prior;
  return n;
}

TEST(ConsistentFit, InconsistentLeastSquaresEstimateEndsConsistentForALittleCost) {
  int repaired = 0;
  for (std::uint64_t seed = 100; seed < 110; ++seed) {
    const NoisyCase n = noisy_case(seed);
    const ConsistencyReport before = check_consistency(n.c.structure, n.problem.unconstrained);
    if (before.consistent()) continue;  // this draw of the noise happened to stay consistent
    ++repaired;
    const ConsistentFitSummary summary = fit_consistent(n.c.structure, n.problem);
    SCOPED_TRACE(summary.brief_report());
    EXPECT_TRUE(summary.converged());
    std::string findings;
    for (const std::string& finding : summary.report.findings) findings += finding + "\n";
    EXPECT_TRUE(summary.report.consistent()) << findings;
    // The least-squares estimate is the unconstrained minimum: the constrained one costs more,
    // but less than what projecting alone costs, and only a little: 0.1–15 % on these draws
    // (the more inconsistent the least-squares links, the more), so 20 % is the bound.
    EXPECT_GE(summary.cost_increase, -1e-12 * summary.unconstrained_cost);
    EXPECT_LT(summary.final_cost, summary.projection_cost);
    EXPECT_LE(summary.final_cost, summary.initial_cost);
    EXPECT_LT(summary.relative_cost_increase, 0.2);
    EXPECT_FALSE(summary.projected_links.empty() && summary.clipped_entries.empty());
    // Non-negative entries stay ≥ 0; the prior term is a small part of the objective.
    for (int index : n.c.structure.non_negative) EXPECT_GE(summary.estimate[index], 0.0);
    EXPECT_LT(summary.regularization_ratio, 0.02);
  }
  EXPECT_GE(repaired, 5);  // the test is about inconsistent estimates: most draws must be
}

TEST(ConsistentFit, NegativeFrictionEstimateEndsExactlyAtItsBound) {
  // Coulomb friction of joint 1 is 0 in truth; give the least-squares estimate a clearly
  // negative value through the data, and the fit must stop on the bound, not near it.
  std::mt19937_64 engine(31);
  Case c = make_case(2, engine);
  const int p = c.structure.parameter_count;
  const int fc1 = 21;
  c.truth[fc1] = 0.0;
  ConsistentFitProblem problem;
  problem.R = random_regressor(2 * p, c.scale, engine);
  // Make fc1's column orthogonal to the others, so that what the data say about fc1 cannot be
  // absorbed elsewhere: the constrained minimum is then the truth with fc1 on its bound.
  const Eigen::MatrixXd others = (Eigen::MatrixXd(problem.R.rows(), p - 1) << problem.R.leftCols(fc1),
                                  problem.R.rightCols(p - fc1 - 1)).finished();
  const Eigen::VectorXd column = problem.R.col(fc1);
  problem.R.col(fc1) = column - others * others.colPivHouseholderQr().solve(column);
  Eigen::VectorXd pulled = c.truth;
  pulled[fc1] = -0.3;  // the data "want" −0.3 N·m: no joint has that
  problem.z = problem.R * pulled;
  problem.unconstrained = pulled;
  problem.prior = c.prior;
  const ConsistentFitSummary summary = fit_consistent(c.structure, problem);
  EXPECT_TRUE(summary.converged()) << summary.brief_report();
  EXPECT_EQ(summary.clipped_entries, std::vector<int>{fc1});
  EXPECT_EQ(summary.estimate[fc1], 0.0);  // on the bound, not near it
  // The cost of the bound: exactly fc1's column times 0.3, squared.
  EXPECT_NEAR(summary.cost_increase, std::pow(0.3 * problem.R.col(fc1).norm(), 2), 1e-6 * summary.cost_increase);
  // KKT: at the bound the cost increases inward.
  const Eigen::VectorXd w = problem.R.transpose() * (problem.R * summary.estimate - problem.z);
  EXPECT_GT(w[fc1], 0.0);
  // Everything else is the truth, up to the prior's pull (ε·κ²).
  EXPECT_LT(scaled_error(summary.estimate, c.truth, c.scale), 1e-6);
}

TEST(ConsistentFit, DirectionsTheDataCannotSeeStayAtThePrior) {
  std::mt19937_64 engine(41);
  Case c = make_case(3, engine);
  const int p = c.structure.parameter_count;
  const int k = 6;  // null-space dimension
  // R = A (I − N Nᵀ) S⁻¹ with N orthonormal (p×k) in scaled coordinates u = S⁻¹π: the data see
  // nothing along S N. The prior differs from the truth only along S N: both explain the data
  // exactly, and only the prior has no prior term, so the fit must return the prior — the CAD
  // values along what the data cannot see — not the truth.
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd random(p, k);
  for (Eigen::Index i = 0; i < random.size(); ++i) random.data()[i] = normal(engine);
  const Eigen::MatrixXd null_basis = Eigen::HouseholderQR<Eigen::MatrixXd>(random).householderQ() *
                                     Eigen::MatrixXd::Identity(p, k);
  Eigen::VectorXd along(k);
  for (int i = 0; i < k; ++i) along[i] = 1e-3 * normal(engine);
  c.prior = c.truth + c.scale.asDiagonal() * (null_basis * along);
  ASSERT_TRUE(check_consistency(c.structure, c.prior).consistent());
  const Eigen::MatrixXd a = random_regressor(2 * p, Eigen::VectorXd::Ones(p), engine);
  ConsistentFitProblem problem;
  problem.R = a * (Eigen::MatrixXd::Identity(p, p) - null_basis * null_basis.transpose()) *
              c.scale.cwiseInverse().asDiagonal();
  problem.z = problem.R * c.truth;
  // The minimum-norm least-squares estimate puts the null-space part at 0, far from CAD.
  problem.unconstrained = problem.R.completeOrthogonalDecomposition().solve(problem.z);
  problem.prior = c.prior;
  ConsistentFitOptions options;
  options.parameter_scale = c.scale;
  const ConsistentFitSummary summary = fit_consistent(c.structure, problem, options);
  SCOPED_TRACE(summary.brief_report());
  EXPECT_TRUE(summary.converged());
  EXPECT_TRUE(summary.report.consistent());
  EXPECT_LT(scaled_error(summary.estimate, c.prior, c.scale), 1e-8);
  EXPECT_GT(scaled_error(c.truth, c.prior, c.scale), 1e-4);  // so it is not the truth
  // Along the null space in scaled coordinates: the prior's components.
  const Eigen::VectorXd u_fit = summary.estimate.cwiseQuotient(c.scale);
  const Eigen::VectorXd u_prior = c.prior.cwiseQuotient(c.scale);
  EXPECT_LT((null_basis.transpose() * (u_fit - u_prior)).norm(), 1e-7);
  // The data are fit as well as by least squares.
  EXPECT_LT(summary.final_cost, 1e-20 * problem.z.squaredNorm());
}

TEST(ConsistentFit, NullSpaceOfARealisticPriorIsPulledToIt) {
  // The prior now also differs along what the data see: there the data win (up to ε·κ²), and
  // along the null space the fit goes to the prior. The expected answer is the truth's part
  // along what the data see plus the prior's along the null space (chosen consistent, so that
  // no constraint is active).
  std::mt19937_64 engine(42);
  Case c = make_case(3, engine);
  const int p = c.structure.parameter_count;
  const int k = 4;
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd random(p, k);
  for (Eigen::Index i = 0; i < random.size(); ++i) random.data()[i] = normal(engine);
  const Eigen::MatrixXd null_basis = Eigen::HouseholderQR<Eigen::MatrixXd>(random).householderQ() *
                                     Eigen::MatrixXd::Identity(p, k);
  Eigen::VectorXd offset(p);
  for (int i = 0; i < p; ++i) offset[i] = 2e-3 * normal(engine);  // CAD errors along every direction
  c.prior = c.truth + c.scale.cwiseProduct(offset);
  const Eigen::VectorXd expected =
      c.truth + c.scale.cwiseProduct(null_basis * (null_basis.transpose() * offset));
  ASSERT_TRUE(check_consistency(c.structure, c.prior).consistent());
  ASSERT_TRUE(check_consistency(c.structure, expected).consistent());
  ConsistentFitProblem problem;
  problem.R = random_regressor(2 * p, Eigen::VectorXd::Ones(p), engine) *
              (Eigen::MatrixXd::Identity(p, p) - null_basis * null_basis.transpose()) *
              c.scale.cwiseInverse().asDiagonal();
  problem.z = problem.R * c.truth;
  problem.unconstrained = problem.R.completeOrthogonalDecomposition().solve(problem.z);
  problem.prior = c.prior;
  ConsistentFitOptions options;
  options.parameter_scale = c.scale;
  const ConsistentFitSummary summary = fit_consistent(c.structure, problem, options);
  SCOPED_TRACE(summary.brief_report());
  EXPECT_TRUE(summary.converged());
  // The answer, up to the prior's pull along what the data see (ε·κ² of the 2e-3 offsets).
  EXPECT_LT(scaled_error(summary.estimate, expected, c.scale), 1e-8);
  EXPECT_GT(scaled_error(c.truth, expected, c.scale), 1e-4);  // not the truth: the prior along N
  // Along the null space: the prior's values (the minimum-norm start had them far away).
  const Eigen::VectorXd fit_offset = (summary.estimate - c.prior).cwiseQuotient(c.scale);
  const Eigen::VectorXd start_offset = (problem.unconstrained - c.prior).cwiseQuotient(c.scale);
  EXPECT_LT((null_basis.transpose() * fit_offset).norm(), 1e-6 * (null_basis.transpose() * start_offset).norm());
  EXPECT_LT(std::sqrt(summary.final_cost), 1e-8 * problem.z.norm());
}

TEST(ConsistentFit, LinkEntriesTheRegressorNeverSeesTakeThePriorsValues) {
  // As for a first link turning about z: only its Izz enters the torques. Least squares (minimum
  // norm) returns 0 for its other nine entries, an inconsistent link; the fit keeps Izz from the
  // data and takes the rest from the prior (here the data's Izz is the prior's, so the whole
  // link must come back as the prior).
  std::mt19937_64 engine(51);
  Case c = make_case(2, engine);
  const int p = c.structure.parameter_count;
  ConsistentFitProblem problem;
  problem.R = random_regressor(2 * p, c.scale, engine);
  problem.R.leftCols(9).setZero();
  // Link 1's CAD values are right (its Izz is what the data see).
  c.truth.head(10) = c.prior.head(10);
  problem.z = problem.R * c.truth;
  problem.unconstrained = problem.R.completeOrthogonalDecomposition().solve(problem.z);
  ASSERT_LT(problem.unconstrained.head(9).cwiseAbs().maxCoeff(), 1e-12);
  ASSERT_FALSE(check_link(problem.unconstrained.head<10>(), "link1").consistent());
  problem.prior = c.prior;
  const ConsistentFitSummary summary = fit_consistent(c.structure, problem);
  SCOPED_TRACE(summary.brief_report());
  EXPECT_TRUE(summary.converged());
  EXPECT_LT(scaled_error(summary.estimate.head(10), c.prior.head(10), c.scale.head(10)), 1e-6);
  EXPECT_LT(scaled_error(summary.estimate.tail(p - 10), c.truth.tail(p - 10), c.scale.tail(p - 10)), 1e-6);

}

TEST(ConsistentFit, TallRegressorIsReducedExactly) {
  // Passing the stacked rows or their triangular factor (with the rest as residual_offset) is
  // the same problem: the same estimate and the same costs.
  const NoisyCase n = noisy_case(103);
  const ConsistentFitSummary tall = fit_consistent(n.c.structure, n.problem);
  const int p = n.c.structure.parameter_count;
  Eigen::MatrixXd augmented(n.problem.R.rows(), p + 1);
  augmented << n.problem.R, n.problem.z;
  const Eigen::MatrixXd t =
      Eigen::HouseholderQR<Eigen::MatrixXd>(augmented).matrixQR().topRows(p + 1).triangularView<Eigen::Upper>();
  ConsistentFitProblem square = n.problem;
  square.R = t.topLeftCorner(p, p);
  square.z = t.col(p).head(p);
  square.residual_offset = t(p, p) * t(p, p);
  const ConsistentFitSummary reduced = fit_consistent(n.c.structure, square);
  EXPECT_LT(scaled_error(tall.estimate, reduced.estimate, tall.parameter_scale), 1e-9);
  EXPECT_NEAR(tall.final_cost, reduced.final_cost, 1e-10 * tall.final_cost);
  EXPECT_NEAR(tall.unconstrained_cost, reduced.unconstrained_cost, 1e-10 * tall.unconstrained_cost);
  EXPECT_NEAR(tall.unconstrained_cost, (n.problem.R * n.problem.unconstrained - n.problem.z).squaredNorm(),
              1e-10 * tall.unconstrained_cost);
}

TEST(ConsistentFit, DerivedParameterScaleFollowsTheDocumentedRule) {
  const NoisyCase n = noisy_case(104);
  const ConsistentFitSummary summary = fit_consistent(n.c.structure, n.problem);
  // Links: (m, mL, mL²) of the prior link — the test case's own scale is built the same way.
  EXPECT_LT(scaled_error(summary.parameter_scale.head(30), n.c.scale.head(30), n.c.scale.head(30)), 1e-14);
  // Friction: as visible to the data as an average link entry, ‖R_j‖·s_j = RMS_links(‖R_i‖·s_i).
  const Eigen::VectorXd norms = n.problem.R.colwise().norm().transpose();
  const double rms = std::sqrt((norms.head(30).cwiseProduct(summary.parameter_scale.head(30))).squaredNorm() / 30.0);
  for (int i = 30; i < 39; ++i) EXPECT_NEAR(norms[i] * summary.parameter_scale[i], rms, 1e-10 * rms);
}

TEST(ConsistentFit, ProgressIsReportedAndTheObjectiveNeverIncreases) {
  const NoisyCase n = noisy_case(105);
  ConsistentFitOptions options;
  std::vector<FitIteration> seen;
  std::vector<double> objective;
  options.on_iteration = [&](const FitIteration& iteration) {
    seen.push_back(iteration);
    ASSERT_NE(iteration.estimate, nullptr);
    EXPECT_TRUE(check_consistency(n.c.structure, *iteration.estimate).links[1].consistent());
    objective.push_back(iteration.data_cost + iteration.regularization_cost + iteration.barrier_cost);
  };
  const ConsistentFitSummary summary = fit_consistent(n.c.structure, n.problem, options);
  ASSERT_EQ(static_cast<int>(seen.size()), summary.iterations);
  for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i].iteration, static_cast<int>(i) + 1);
  for (std::size_t i = 1; i < objective.size(); ++i) EXPECT_LE(objective[i], objective[i - 1]);
  EXPECT_DOUBLE_EQ(seen.back().data_cost, summary.final_cost);
}

TEST(ConsistentFit, CancelFlagStopsAtTheNextIteration) {
  const NoisyCase n = noisy_case(106);
  std::atomic<bool> cancel{false};
  ConsistentFitOptions options;
  options.cancel = &cancel;
  options.on_iteration = [&](const FitIteration& iteration) {
    if (iteration.iteration == 2) cancel = true;
  };
  const ConsistentFitSummary summary = fit_consistent(n.c.structure, n.problem, options);
  EXPECT_EQ(summary.termination, FitTermination::cancelled);
  EXPECT_FALSE(summary.converged());
  EXPECT_EQ(summary.iterations, 2);
  EXPECT_TRUE(summary.report.consistent());  // the best so far is still a consistent estimate

  // Set before the start: no iteration at all, the (projected, clipped) start comes back.
  ConsistentFitOptions already;
  already.cancel = &cancel;
  const ConsistentFitSummary none = fit_consistent(n.c.structure, n.problem, already);
  EXPECT_EQ(none.termination, FitTermination::cancelled);
  EXPECT_EQ(none.iterations, 0);
  EXPECT_TRUE(none.estimate == none.start);
}

TEST(ConsistentFit, MaxIterationsIsReportedAsNotConverged) {
  const NoisyCase n = noisy_case(107);
  ConsistentFitOptions options;
  options.max_iterations = 1;
  const ConsistentFitSummary summary = fit_consistent(n.c.structure, n.problem, options);
  EXPECT_EQ(summary.termination, FitTermination::max_iterations);
  EXPECT_EQ(summary.iterations, 1);
  EXPECT_NE(summary.message.find("max_iterations"), std::string::npos);
}

TEST(ConsistentFit, BadInputNamesTheField) {
  const NoisyCase n = noisy_case(108);
  const ParameterStructure& structure = n.c.structure;
  auto fit = [&](const ConsistentFitProblem& problem, const ConsistentFitOptions& options = {}) {
    return field_of([&] { fit_consistent(structure, problem, options); });
  };
  ConsistentFitProblem bad = n.problem;
  bad.R(3, 5) = std::nan("");
  EXPECT_EQ(fit(bad), "R");
  bad = n.problem;
  bad.R(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(fit(bad), "R");
  bad = n.problem;
  bad.R = Eigen::MatrixXd(0, structure.parameter_count);
  bad.z.resize(0);
  EXPECT_EQ(fit(bad), "R");
  bad = n.problem;
  bad.R = bad.R.leftCols(structure.parameter_count - 1).eval();
  EXPECT_EQ(fit(bad), "R");
  bad = n.problem;
  bad.R.setZero();
  EXPECT_EQ(fit(bad), "R");
  bad = n.problem;
  bad.z.conservativeResize(bad.z.size() - 1);
  EXPECT_EQ(fit(bad), "z");
  bad = n.problem;
  bad.z[0] = std::nan("");
  EXPECT_EQ(fit(bad), "z");
  bad = n.problem;
  bad.unconstrained.conservativeResize(10);
  EXPECT_EQ(fit(bad), "unconstrained");
  bad = n.problem;
  bad.unconstrained[2] = std::nan("");
  EXPECT_EQ(fit(bad), "unconstrained");
  bad = n.problem;
  bad.prior.resize(0);
  EXPECT_EQ(fit(bad), "prior");
  bad = n.problem;
  bad.start = Eigen::VectorXd::Zero(3);
  EXPECT_EQ(fit(bad), "start");
  bad = n.problem;
  bad.residual_offset = -1.0;
  EXPECT_EQ(fit(bad), "residual_offset");

  ConsistentFitOptions options;
  options.regularization = -1e-8;
  EXPECT_EQ(fit(n.problem, options), "options.regularization");
  options = {};
  options.parameter_scale = Eigen::VectorXd::Zero(structure.parameter_count);
  EXPECT_EQ(fit(n.problem, options), "options.parameter_scale");
  options = {};
  options.function_tolerance = std::nan("");
  EXPECT_EQ(fit(n.problem, options), "options.function_tolerance");
  options = {};
  options.projection.relative_floor = 2.0;
  EXPECT_EQ(fit(n.problem, options), "options.projection.relative_floor");

  ParameterStructure broken = structure;
  broken.link_offsets.back() = 5;
  EXPECT_EQ(field_of([&] { fit_consistent(broken, n.problem); }), "structure.link_offsets");
  // A prior with nothing positive where the estimate has nothing positive either.
  // m = −1 kg, h = 0, I_O = −2E kg·m²: J = −E.
  bad = n.problem;
  bad.unconstrained.head<10>() << -1.0, 0.0, 0.0, 0.0, -2.0, 0.0, 0.0, -2.0, 0.0, -2.0;
  bad.prior.head<10>() = bad.unconstrained.head<10>();
  EXPECT_EQ(fit(bad), "prior");
}

}  // namespace
}  // namespace manipid::robot

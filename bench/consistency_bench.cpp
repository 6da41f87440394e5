// consistency_bench.cpp — the consistent fit of a 7-link arm with 21 friction parameters (p = 91).
//
// R is the triangular factor of a random, well-scaled stacked regressor (4p rows, columns at
// each parameter's natural size), z the torques of a truth with one slender link and a joint
// without Coulomb friction plus 1 % noise, so the least-squares estimate is inconsistent — the
// case the fit exists for. Two variants: full rank, and rank-deficient like a real arm (27 of
// the 91 directions unseen: 64 base parameters, as for the Panda and KUKA logs).
#include "manipid/core/robot/consistent_fit.h"
#include "manipid/core/robot/log_cholesky.h"

#include <Eigen/QR>
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <string>

namespace manipid::robot {
namespace {

constexpr int kLinks = 7;

struct Arm {
  ParameterStructure structure;
  ConsistentFitProblem problem;
};

Arm make_arm(int unseen_directions, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  Arm arm;
  ParameterStructure& s = arm.structure;
  s.parameter_count = 13 * kLinks;
  const char* inertial[10] = {"m", "mx", "my", "mz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"};
  for (int k = 0; k < kLinks; ++k) {
    s.link_offsets.push_back(10 * k);
    s.link_names.push_back("link" + std::to_string(k + 1));
    for (const char* name : inertial) s.parameter_names.push_back(name + std::to_string(k + 1));
  }
  for (int k = 0; k < kLinks; ++k) {
    s.non_negative.push_back(10 * kLinks + 3 * k);
    s.non_negative.push_back(10 * kLinks + 3 * k + 1);
    for (const char* name : {"fv", "fc", "fo"}) s.parameter_names.push_back(name + std::to_string(k + 1));
  }
  const int p = s.parameter_count;

  // Truth and CAD prior (θ nudged), and each entry's natural size.
  std::uniform_real_distribution<double> alpha(-0.5, 2.0), d(-3.0, -1.2), coupling(-0.1, 0.1), com(-0.2, 0.2);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd truth(p), prior(p), scale(p);
  for (int k = 0; k < kLinks; ++k) {
    LogCholesky theta;
    theta << alpha(engine), d(engine), d(engine), d(engine), coupling(engine), coupling(engine), coupling(engine),
        com(engine), com(engine), com(engine);
    if (k == 5) theta[3] = std::log(2e-3);  // a slender link: 2 mm radius of gyration across
    LogCholesky near = theta;
    for (int i = 0; i < 10; ++i) near[i] += 0.05 * normal(engine);
    truth.segment<10>(10 * k) = standard_from_log_cholesky(theta);
    const Vector10d cad = standard_from_log_cholesky(near);
    prior.segment<10>(10 * k) = cad;
    const double length = std::sqrt(0.5 * (cad[4] + cad[7] + cad[9]) / cad[0]);
    scale.segment<10>(10 * k) << cad[0], Eigen::Vector3d::Constant(cad[0] * length),
        Eigen::Matrix<double, 6, 1>::Constant(cad[0] * length * length);
  }
  std::uniform_real_distribution<double> viscous(0.1, 2.0), coulomb(0.1, 3.0), offset(-0.5, 0.5);
  for (int k = 0; k < kLinks; ++k) {
    const int base = 10 * kLinks + 3 * k;
    truth.segment<3>(base) << viscous(engine), k == 2 ? 0.0 : coulomb(engine), offset(engine);
    for (int i = 0; i < 3; ++i) prior[base + i] = truth[base + i] * (1.0 + 0.2 * normal(engine));
    scale.segment<3>(base) = truth.segment<3>(base).cwiseAbs().cwiseMax(0.1);
  }

  // The stacked regressor (4p rows, columns at natural size), optionally blind along some
  // directions, reduced to its triangular factor as the identification does.
  Eigen::MatrixXd stacked(4 * p, p);
  for (Eigen::Index i = 0; i < stacked.size(); ++i) stacked.data()[i] = normal(engine);
  if (unseen_directions > 0) {
    Eigen::MatrixXd random(p, unseen_directions);
    for (Eigen::Index i = 0; i < random.size(); ++i) random.data()[i] = normal(engine);
    const Eigen::MatrixXd null_basis =
        Eigen::HouseholderQR<Eigen::MatrixXd>(random).householderQ() * Eigen::MatrixXd::Identity(p, unseen_directions);
    stacked = stacked * (Eigen::MatrixXd::Identity(p, p) - null_basis * null_basis.transpose());
  }
  stacked = stacked * scale.cwiseInverse().asDiagonal();
  Eigen::VectorXd torque = stacked * truth;
  const double sigma = 0.01 * torque.norm() / std::sqrt(double(torque.size()));
  for (Eigen::Index i = 0; i < torque.size(); ++i) torque[i] += sigma * normal(engine);
  Eigen::MatrixXd augmented(stacked.rows(), p + 1);
  augmented << stacked, torque;
  const Eigen::MatrixXd triangle =
      Eigen::HouseholderQR<Eigen::MatrixXd>(augmented).matrixQR().topRows(p + 1).triangularView<Eigen::Upper>();
  arm.problem.R = triangle.topLeftCorner(p, p);
  arm.problem.z = triangle.col(p).head(p);
  arm.problem.residual_offset = triangle(p, p) * triangle(p, p);
  arm.problem.unconstrained = arm.problem.R.completeOrthogonalDecomposition().solve(arm.problem.z);
  arm.problem.prior = prior;
  return arm;
}

void fit(benchmark::State& state, int unseen_directions) {
  const Arm arm = make_arm(unseen_directions, 7);
  ConsistentFitSummary summary;
  for (auto _ : state) {
    summary = fit_consistent(arm.structure, arm.problem);
    benchmark::DoNotOptimize(summary.estimate.data());
  }
  const ConsistencyReport before = check_consistency(arm.structure, arm.problem.unconstrained);
  state.counters["p"] = arm.structure.parameter_count;
  state.counters["inconsistent_links_LS"] = static_cast<double>(before.inconsistent_links().size());
  state.counters["iterations"] = summary.iterations;
  state.counters["converged"] = summary.converged() ? 1 : 0;
  state.counters["consistent"] = summary.report.consistent() ? 1 : 0;
  state.counters["cost_increase_pct"] = 100.0 * summary.relative_cost_increase;
}

void BM_ConsistentFit_FullRank(benchmark::State& state) { fit(state, 0); }
void BM_ConsistentFit_RankDeficient(benchmark::State& state) { fit(state, 27); }

BENCHMARK(BM_ConsistentFit_FullRank)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ConsistentFit_RankDeficient)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace manipid::robot

// robot_bench.cpp — manipid's robot RNEA and regressor beside KDL's ChainIdSolver_RNE, Panda-like 7-DOF arm.
//
// Both solvers run on the same chain (KDL's built straight from urdfdom, tests/core/robot/kdl_reference.h)
// and cycle through the same 1,024 random states, so neither benefits from a repeated input. KDL's solver
// computes the rigid-body torque only; manipid's RNEA is timed with the same rigid-body layout, and with
// the default layout (viscous + Coulomb friction) to show what friction costs.
#include "kdl_reference.h"
#include "manipid/core/robot/regressor.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/core/robot/urdf.h"

#include <benchmark/benchmark.h>

#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

namespace manipid::robot {
namespace {

std::string panda_like_urdf() {
  const std::string path = std::string(MANIPID_SOURCE_DIR) + "/examples/robots/panda_like.urdf";
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

constexpr int kStates = 1024;

struct Fixture {
  std::string xml = panda_like_urdf();
  Model model = parse_urdf(xml).model;
  int n = model.joint_count();
  Eigen::MatrixXd q, qd, qdd;  // n × kStates
  Fixture() : q(n, kStates), qd(n, kStates), qdd(n, kStates) {
    std::mt19937_64 engine(3);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    for (int s = 0; s < kStates; ++s) {
      for (int k = 0; k < n; ++k) {
        q(k, s) = 3.0 * uniform(engine);
        qd(k, s) = 2.0 * uniform(engine);
        qdd(k, s) = 10.0 * uniform(engine);
      }
    }
  }
};

const Fixture& fixture() {
  static const Fixture instance;
  return instance;
}

void BM_RneaManipid(benchmark::State& state, ParameterLayout layout) {
  const Fixture& f = fixture();
  Data data(f.model);
  const Eigen::VectorXd pi = standard_parameters(f.model, layout);
  Eigen::VectorXd tau(f.n);
  int s = 0;
  for (auto _ : state) {
    inverse_dynamics(f.model, data, layout, pi, f.q.col(s), f.qd.col(s), f.qdd.col(s), tau);
    benchmark::DoNotOptimize(tau.data());
    benchmark::ClobberMemory();
    s = (s + 1) % kStates;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_RneaManipid, rigid_body, ParameterLayout{.viscous = false, .coulomb = false});
BENCHMARK_CAPTURE(BM_RneaManipid, with_friction, ParameterLayout{});

void BM_RneaKdl(benchmark::State& state) {
  const Fixture& f = fixture();
  const auto urdf = testing::kdl::parse(f.xml);
  testing::kdl::ChainDynamics kdl(testing::kdl::chain(*urdf, f.model.base_link, f.model.tip_link), f.model.gravity);
  // States converted to KDL's arrays up front: the loop times the solver alone.
  std::vector<KDL::JntArray> q, qd, qdd;
  for (int s = 0; s < kStates; ++s) {
    q.push_back(testing::kdl::joint_array(f.q.col(s)));
    qd.push_back(testing::kdl::joint_array(f.qd.col(s)));
    qdd.push_back(testing::kdl::joint_array(f.qdd.col(s)));
  }
  int s = 0;
  for (auto _ : state) {
    const KDL::JntArray& tau = kdl.torque(q[s], qd[s], qdd[s]);
    benchmark::DoNotOptimize(tau.data.data());
    benchmark::ClobberMemory();
    s = (s + 1) % kStates;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RneaKdl);

void BM_Regressor(benchmark::State& state) {
  const Fixture& f = fixture();
  const ParameterLayout layout{.offset = true};
  Data data(f.model);
  Eigen::MatrixXd Y(f.n, layout.size(f.n));
  int s = 0;
  for (auto _ : state) {
    regressor(f.model, data, layout, f.q.col(s), f.qd.col(s), f.qdd.col(s), Y);
    benchmark::DoNotOptimize(Y.data());
    benchmark::ClobberMemory();
    s = (s + 1) % kStates;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Regressor);

/// The whole stacked regressor for kStates samples (items = samples).
void BM_StackedRegressor(benchmark::State& state) {
  const Fixture& f = fixture();
  const ParameterLayout layout{.offset = true};
  Data data(f.model);
  Eigen::MatrixXd Y(kStates * f.n, layout.size(f.n));
  for (auto _ : state) {
    stacked_regressor(f.model, data, layout, f.q, f.qd, f.qdd, Y);
    benchmark::DoNotOptimize(Y.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * kStates);
}
BENCHMARK(BM_StackedRegressor);

}  // namespace
}  // namespace manipid::robot

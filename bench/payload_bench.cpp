// payload_bench.cpp — a payload identification on the UR5-like arm from 15,000 samples (15 s at 1 kHz; target ≤ 50 ms on one core).
//
// The data: a 5-harmonic Fourier motion of period 15 s, torques from the URDF's values with viscous and
// Coulomb friction and a 3 kg tool off the flange's axis; the arm given as its true standard vector.
#include "manipid/core/robot/payload.h"
#include "manipid/core/robot/urdf.h"

#include "robot_test_support.h"
#include "simulated_runs.h"

#include <benchmark/benchmark.h>

#include <random>

namespace manipid::robot {
namespace {

struct PayloadRun {
  Model model = parse_urdf(testing::read_file(testing::source_path("examples/robots/ur5_like.urdf"))).model;
  ArmParameters arm;
  Trajectory data;

  PayloadRun() {
    arm.pi = standard_parameters(model, arm.layout);
    const InertialParameters tool =
        InertialParameters::from_centre_of_mass(3.0, Eigen::Vector3d(0.04, -0.03, 0.09), Eigen::Vector3d(0.01, 0.012, 0.006).asDiagonal());
    std::mt19937_64 engine(1);
    testing::Fourier motion = testing::Fourier::random(model.joint_count(), 5, engine, 0.4);
    motion.period = 15.0;
    data = testing::measure(model, arm.layout, with_payload(model, arm, tool.vector()), motion,
                            Eigen::VectorXd::LinSpaced(15'000, 0.0, 14.999));
  }
};

void BM_Payload_UR5like_15000(benchmark::State& state) {
  static const PayloadRun run;
  for (auto _ : state) {
    const PayloadResult result = identify_payload(run.model, run.arm, {run.data}, {});
    benchmark::DoNotOptimize(result.mass);
  }
}
BENCHMARK(BM_Payload_UR5like_15000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace manipid::robot

// dynamics_count.cpp — exactly 1,000 dynamics calls on the paper's robot, for instruction
// counts that do not depend on timing (Google Benchmark picks its own iteration counts):
//
//   valgrind --tool=callgrind --toggle-collect='manipid::inverse_dynamics(*'
//            build/release/bench/dynamics_count inverse complete
//
// and divide the collected instructions by 1,000. Arguments: inverse|forward complete|paper.
// Prints a checksum of the results, so before/after builds can be compared as well.
#include "manipid/core/paper/dynamics.h"
#include "manipid/core/paper/presets.h"

#include <cstdio>
#include <random>
#include <string>

int main(int argc, char** argv) {
  using namespace manipid;
  const bool forward = argc > 1 && std::string(argv[1]) == "forward";
  const bool paper = argc > 2 && std::string(argv[2]) == "paper";
  const Preset preset = cedro2009(paper ? KineticEnergy::paper : KineticEnergy::complete);
  DynamicsWorkspace workspace(preset.model);
  const int samples = 1000;
  Eigen::MatrixXd q(4, samples), qd(4, samples), input(4, samples);  // input: q̈ or τ
  std::mt19937_64 engine(3);
  std::uniform_real_distribution<double> uniform(-2.0, 2.0);
  for (Eigen::MatrixXd* m : {&q, &qd, &input}) {
    for (Eigen::Index i = 0; i < m->size(); ++i) m->data()[i] = uniform(engine);
  }
  Eigen::VectorXd output(4);
  double checksum = 0.0;
  for (int i = 0; i < samples; ++i) {
    if (forward) {
      forward_dynamics(preset.model, preset.true_parameters, workspace, q.col(i), qd.col(i), input.col(i), output);
    } else {
      inverse_dynamics(preset.model, preset.true_parameters, workspace, q.col(i), qd.col(i), input.col(i), output);
    }
    checksum += output.sum();
  }
  std::printf("%.17g\n", checksum);
}

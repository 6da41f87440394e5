// test_models.h — robots shared by the core tests: the paper's preset and a deliberately
// irregular chain (twists, d-type lengths, fixed offsets, tilted gravity) that exercises
// every branch of the kinematics.
#pragma once

#include "manipid/core/paper/model.h"
#include "manipid/core/paper/presets.h"

#include <Eigen/Core>

#include <random>

namespace manipid::testing {

inline RobotModel irregular_model(KineticEnergy kinetic_energy) {
  RobotModel model;
  model.joints = {
      {.alpha = 0.3, .a = 0.1, .d = 0.0, .length_role = LengthRole::d},
      {.alpha = -0.7, .a = 0.0, .d = 0.05, .length_role = LengthRole::a},
      {.alpha = 1.1, .a = 0.15, .d = 0.1, .length_role = LengthRole::none},
      {.alpha = 0.0, .a = 0.0, .d = 0.0, .length_role = LengthRole::a},
  };
  model.gravity = Eigen::Vector3d(0.5, -1.2, -9.6);
  model.kinetic_energy = kinetic_energy;
  return model;
}

inline Parameters irregular_parameters() {
  return Parameters(Eigen::Vector4d(3.0, 2.0, 1.5, 0.7), Eigen::Vector4d(0.3, 0.5, 0.25, 0.4));
}

/// Uniform random vector in [-scale, scale]^n from a seeded engine.
inline Eigen::VectorXd random_vector(std::mt19937_64& engine, int n, double scale) {
  std::uniform_real_distribution<double> uniform(-scale, scale);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = uniform(engine);
  return v;
}

}  // namespace manipid::testing

// presets.h — named robots with their true parameters, controller gains and experiment.
//
// `cedro2009` is the 4-DOF manipulator of Cedro & Janecki, "Identification of a manipulator
// model using the input error method in the Mathematica program" (the seed paper):
//   T1 = Rz(φ1)·Rx(+90°) with no offset; T2..T4 = Rz(φk)·Tx(l_k);
//   gravity as printed, V_k = -m_k (0,0,g)·p_k with g = 9.81 (gravity along +z);
//   l = (0.4, 0.8, 0.6, 0.2) m, m = (50, 25, 15, 5) kg;
//   PD gains Kp = (3800, 40000, 10000, 500), Kd = (159.5, 120, 50, 2);
//   reference: 0.5 rad steps at 1, 3, 5, 7 s, pre-filtered (M = 100, Ωg = 0.025), horizon 9.7 s;
//   identification starts from (50.1, 25.1, 15.1, 5.1, 0.41, 0.79, 0.59, 0.19).
// The paper prints r = (0,0,0,0) for the point of each frame; it means the homogeneous
// origin (0,0,0,1), which is what the model uses.
#pragma once

#include "manipid/core/paper/model.h"
#include "manipid/core/paper/simulation.h"

#include <optional>
#include <string>
#include <vector>

namespace manipid {

struct Preset {
  std::string name;
  std::string description;
  RobotModel model;
  Parameters true_parameters;
  Parameters initial_parameters;  ///< where the paper's identification starts
  PdController controller;
  StepReferenceSpec reference;
  SimulationOptions simulation;
};

/// The paper's robot and experiment (see the file comment).
Preset cedro2009(KineticEnergy kinetic_energy = KineticEnergy::complete);

/// Looks a preset up by name; throws InputError("preset", ...) listing the known names.
Preset find_preset(const std::string& name, KineticEnergy kinetic_energy = KineticEnergy::complete);
std::vector<std::string> preset_names();

}  // namespace manipid

// presets.cpp — the named robots users can ask for (presets.h).
#include "manipid/core/paper/presets.h"

#include <numbers>

namespace manipid {

Preset cedro2009(KineticEnergy kinetic_energy) {
  Preset preset;
  preset.name = "cedro2009";
  preset.description =
      "Cedro & Janecki's 4-DOF manipulator: point masses at the link ends, PD control, "
      "0.5 rad steps at 1, 3, 5, 7 s";

  RobotModel& model = preset.model;
  // T1 = Rz(φ1)·Rx(+90°): no offset, so l1 enters only through J1 = m1 l1²/12.
  model.joints.push_back({.alpha = std::numbers::pi / 2, .a = 0, .d = 0, .length_role = LengthRole::none});
  // T2..T4 = Rz(φk)·Tx(l_k).
  for (int k = 2; k <= 4; ++k) model.joints.push_back({.alpha = 0, .a = 0, .d = 0, .length_role = LengthRole::a});
  // The paper prints V_k = -m_k (0,0,g)·p_k: gravity acts along +z of its base frame.
  model.gravity = Eigen::Vector3d(0.0, 0.0, 9.81);
  model.kinetic_energy = kinetic_energy;
  model.joint_inertia_factor = 1.0 / 12.0;

  preset.true_parameters = Parameters(Eigen::Vector4d(50, 25, 15, 5), Eigen::Vector4d(0.4, 0.8, 0.6, 0.2));
  preset.initial_parameters =
      Parameters(Eigen::Vector4d(50.1, 25.1, 15.1, 5.1), Eigen::Vector4d(0.41, 0.79, 0.59, 0.19));
  preset.controller.kp = Eigen::Vector4d(3800, 40000, 10000, 500);
  preset.controller.kd = Eigen::Vector4d(159.5, 120, 50, 2);

  preset.reference.step_times = {1.0, 3.0, 5.0, 7.0};
  preset.reference.amplitudes = {0.5, 0.5, 0.5, 0.5};
  preset.reference.duration = 10.0;
  preset.reference.dt = 0.001;
  preset.reference.half_length = 100;
  preset.reference.band = 0.025;

  preset.simulation.duration = 9.7;  // the paper's tk − 0.3
  preset.simulation.dt = 0.001;
  preset.simulation.relative_tolerance = 1e-8;
  return preset;
}

std::vector<std::string> preset_names() { return {"cedro2009"}; }

Preset find_preset(const std::string& name, KineticEnergy kinetic_energy) {
  if (name == "cedro2009") return cedro2009(kinetic_energy);
  std::string known;
  for (const auto& candidate : preset_names()) known += (known.empty() ? "" : ", ") + candidate;
  throw InputError("preset", "unknown preset '" + name + "' (known: " + known + ")");
}

}  // namespace manipid

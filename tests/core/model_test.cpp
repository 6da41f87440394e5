// model_test.cpp — parameter names and validation, presets, and the paper's kinematics
// (its printed T1..T4 multiplied out by hand).
#include "manipid/core/paper/dynamics.h"
#include "manipid/core/paper/presets.h"

#include <gtest/gtest.h>

#include <cmath>

namespace manipid {
namespace {

TEST(Model, ParameterNamesAndIndices) {
  EXPECT_EQ(parameter_names(2), (std::vector<std::string>{"m1", "m2", "l1", "l2"}));
  EXPECT_EQ(parameter_index("m1", 4), 0);
  EXPECT_EQ(parameter_index("l4", 4), 7);
  for (const char* bad : {"m0", "m5", "l01", "x1", "m", "m+1", "m1 ", "M1", ""}) {
    EXPECT_EQ(parameter_index(bad, 4), -1) << bad;
  }
}

TEST(Model, UnknownParameterNamesTheField) {
  Parameters parameters = cedro2009().true_parameters;
  parameters.set("m2", 24.0);
  EXPECT_EQ(parameters.get("m2"), 24.0);
  try {
    parameters.set("m5", 1.0);
    FAIL();
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "m5");
    EXPECT_NE(std::string(error.what()).find("m1..m4"), std::string::npos);
  }
  EXPECT_THROW(parameters.set("l2", std::nan("")), InputError);
}

TEST(Model, UnknownPresetIsAnInputError) {
  try {
    find_preset("puma560");
    FAIL();
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "preset");
    EXPECT_NE(std::string(error.what()).find("cedro2009"), std::string::npos);
  }
  EXPECT_EQ(find_preset("cedro2009", KineticEnergy::paper).model.kinetic_energy, KineticEnergy::paper);
}

TEST(Model, KineticEnergyNames) {
  EXPECT_EQ(parse_kinetic_energy("paper"), KineticEnergy::paper);
  EXPECT_EQ(parse_kinetic_energy("complete"), KineticEnergy::complete);
  EXPECT_THROW(parse_kinetic_energy("full"), InputError);
}

// The paper's matrices, as printed, with r = (0,0,0,1).
Eigen::Matrix4d paper_transform(int k, double phi, double l) {
  const double c = std::cos(phi), s = std::sin(phi);
  Eigen::Matrix4d T;
  if (k == 1) {
    T << c, 0, s, 0, s, 0, -c, 0, 0, 1, 0, 0, 0, 0, 0, 1;
  } else {
    T << c, -s, 0, l * c, s, c, 0, l * s, 0, 0, 1, 0, 0, 0, 0, 1;
  }
  return T;
}

TEST(Model, Cedro2009KinematicsMatchThePaperMatrices) {
  const Preset preset = cedro2009();
  const Eigen::Vector4d q(0.3, -0.8, 1.2, 0.45);
  Eigen::Matrix4d chain = Eigen::Matrix4d::Identity();
  for (int k = 1; k <= 4; ++k) {
    chain = chain * paper_transform(k, q[k - 1], preset.true_parameters.length[k - 1]);
    const Eigen::Vector3d expected = (chain * Eigen::Vector4d(0, 0, 0, 1)).head<3>();
    EXPECT_LE((mass_position(preset.model, preset.true_parameters, q, k) - expected).norm(), 1e-14) << k;
  }
  // V_k = −m_k (0,0,g)·p_k, as printed.
  double expected_potential = 0.0;
  chain.setIdentity();
  for (int k = 1; k <= 4; ++k) {
    chain = chain * paper_transform(k, q[k - 1], preset.true_parameters.length[k - 1]);
    expected_potential -= preset.true_parameters.mass[k - 1] * 9.81 * chain(2, 3);
  }
  EXPECT_NEAR(potential_energy(preset.model, preset.true_parameters, q), expected_potential, 1e-10);
}

}  // namespace
}  // namespace manipid

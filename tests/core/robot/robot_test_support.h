// robot_test_support.h — robot test helpers: test files, random states, physically consistent parameters.
#pragma once

#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

namespace manipid::robot::testing {

/// A file of the source tree (MANIPID_SOURCE_DIR is set by tests/CMakeLists.txt).
inline std::string source_path(const std::string& relative) { return std::string(MANIPID_SOURCE_DIR) + "/" + relative; }

inline std::string read_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// tests/data/robots/arm7.urdf: the irregular 7-DOF test arm with a fixed mount and a fixed flange.
inline std::string arm7_urdf() { return read_file(source_path("tests/data/robots/arm7.urdf")); }

/// The licensed real-robot folder beside the repository (absent in a user's clone: tests skip).
inline std::filesystem::path real_robots_folder() {
  return std::filesystem::path(MANIPID_SOURCE_DIR) / ".." / "shared" / "real-robots";
}

/// `xml` with `text` inserted before its closing </robot>.
inline std::string with_appended(std::string xml, const std::string& text) {
  const std::size_t end = xml.rfind("</robot>");
  if (end == std::string::npos) throw std::runtime_error("no </robot> in the test URDF");
  return xml.insert(end, text);
}

/// `xml` with its first occurrence of `from` replaced by `to` (which must exist).
inline std::string with_replaced(std::string xml, const std::string& from, const std::string& to) {
  const std::size_t at = xml.find(from);
  if (at == std::string::npos) throw std::runtime_error("'" + from + "' not in the test URDF");
  return xml.replace(at, from.size(), to);
}

inline Eigen::VectorXd random_vector(std::mt19937_64& engine, int n, double scale) {
  std::uniform_real_distribution<double> uniform(-scale, scale);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = uniform(engine);
  return v;
}

/// A physically consistent body: mass in [0.5, 5] kg, centre of mass within 0.2 m of the origin, and the
/// inertia of a random point cloud's second moments Σ (I_c = tr(Σ) E − Σ satisfies the triangle inequality),
/// randomly rotated.
inline InertialParameters random_body(std::mt19937_64& engine) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double mass = 0.5 + 4.5 * unit(engine);
  const Eigen::Vector3d com = random_vector(engine, 3, 0.2);
  const Eigen::Vector3d spread(0.001 + 0.02 * unit(engine), 0.001 + 0.02 * unit(engine), 0.001 + 0.02 * unit(engine));
  const Eigen::Matrix3d second_moments = (mass * spread).asDiagonal();
  const Eigen::Matrix3d principal = second_moments.trace() * Eigen::Matrix3d::Identity() - second_moments;
  const Eigen::Matrix3d R = Eigen::Quaterniond(Eigen::Vector4d(random_vector(engine, 4, 1.0)).normalized()).toRotationMatrix();
  return InertialParameters::from_centre_of_mass(mass, com, R * principal * R.transpose());
}

/// Rigid bodies only: no viscous or Coulomb friction columns.
inline const ParameterLayout kRigid{.viscous = false, .coulomb = false};

/// π for `joint_count` joints: random consistent bodies, friction and armature in plausible ranges.
inline Eigen::VectorXd random_parameters(std::mt19937_64& engine, int joint_count, const ParameterLayout& layout) {
  Eigen::VectorXd pi(layout.size(joint_count));
  for (int k = 0; k < joint_count; ++k) pi.segment<10>(10 * k) = random_body(engine).vector();
  std::uniform_real_distribution<double> positive(0.05, 2.0), offset(-1.0, 1.0);
  for (int i = 10 * joint_count; i < pi.size(); ++i) pi[i] = positive(engine);
  if (layout.offset) {
    for (int k = 0; k < joint_count; ++k) pi[layout.offset_begin(joint_count) + k] = offset(engine);
  }
  return pi;
}

/// ‖a − b‖∞ / ‖b‖∞.
inline double relative_error(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).lpNorm<Eigen::Infinity>() / b.lpNorm<Eigen::Infinity>();
}

}  // namespace manipid::robot::testing

// trajectory.h — sampled joint data: what is measured on a robot or produced by simulation.
#pragma once

#include <Eigen/Core>

namespace manipid {

/// The sample periods a trajectory may have, s: a megahertz logger to one sample in ten
/// seconds. Outside them the differential filters' scaling (1/Δ, 1/Δ²) leaves the range
/// where double arithmetic is meaningful, or no robot motion is left to see.
inline constexpr double kShortestSamplePeriod = 1e-6;
inline constexpr double kLongestSamplePeriod = 10.0;

/// Uniformly sampled joint data. Matrices are samples × joints (column-major, so each
/// joint's signal is contiguous). Units: t s, q rad, tau N·m, ref rad.
struct Trajectory {
  Eigen::VectorXd t;
  Eigen::MatrixXd q;
  Eigen::MatrixXd tau;  ///< empty (0 columns) when torque was not measured
  Eigen::MatrixXd ref;  ///< empty (0 columns) when the reference is unknown

  int samples() const { return static_cast<int>(t.size()); }
  int joint_count() const { return static_cast<int>(q.cols()); }
  bool has_torque() const { return tau.cols() > 0; }
  bool has_reference() const { return ref.cols() > 0; }
  /// Sample period from the time column (t[1] − t[0]); 0 with fewer than two samples.
  double dt() const { return samples() > 1 ? t[1] - t[0] : 0.0; }

  /// Throws InputError unless sizes agree, every value is finite and t is increasing and
  /// uniform to a relative 1e-6 of dt, with dt in [kShortestSamplePeriod, kLongestSamplePeriod].
  void validate() const;
};

}  // namespace manipid

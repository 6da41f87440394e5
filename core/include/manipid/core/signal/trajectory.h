// trajectory.h — sampled joint data: what is measured on a robot or produced by simulation.
#pragma once

#include "manipid/core/errors.h"

#include <Eigen/Core>

#include <string>

namespace manipid {

/// The sample periods a trajectory may have, s: a megahertz logger to one sample in ten
/// seconds. Outside them the differential filters' scaling (1/Δ, 1/Δ²) leaves the range
/// where double arithmetic is meaningful, or no robot motion is left to see.
inline constexpr double kShortestSamplePeriod = 1e-6;
inline constexpr double kLongestSamplePeriod = 10.0;

/// Sampled joint data, as measured or simulated. Matrices are samples × joints (column-major,
/// so each joint's signal is contiguous). Units: t s, q rad, qd rad/s, qdd rad/s², tau N·m, ref rad.
/// Time stamps must increase but need not be uniform (real loggers jitter); the algorithms
/// that need one sample period take the data through make_uniform() (resample.h) first.
struct Trajectory {
  Eigen::VectorXd t;
  Eigen::MatrixXd q;
  Eigen::MatrixXd tau;  ///< empty (0 columns) when torque was not measured
  Eigen::MatrixXd ref;  ///< empty (0 columns) when the reference is unknown
  Eigen::MatrixXd qd;   ///< empty (0 columns) unless the logger recorded joint rates; kept, not
                        ///< used by identification (the differential filters make q̇ from q)
  Eigen::MatrixXd qdd;  ///< empty unless recorded (or designed: an excitation's q̈), rad/s²; kept, not used

  int samples() const { return static_cast<int>(t.size()); }
  int joint_count() const { return static_cast<int>(q.cols()); }
  bool has_torque() const { return tau.cols() > 0; }
  bool has_reference() const { return ref.cols() > 0; }
  bool has_rates() const { return qd.cols() > 0; }
  bool has_accelerations() const { return qdd.cols() > 0; }
  /// Sample period of uniform data (t[1] − t[0]); 0 with fewer than two samples.
  double dt() const { return samples() > 1 ? t[1] - t[0] : 0.0; }
  /// The median step of t, s (the typical step of jittery data).
  double median_step() const;
  /// True when every step equals t[1] − t[0] to a relative 1e-6 (printing noise).
  bool is_uniform() const;
  /// The sample period: t[1] − t[0] for uniform data, else the median step, s.
  double sample_period() const { return is_uniform() ? dt() : median_step(); }

  /// Throws InputError unless sizes agree, every value is finite, t strictly increases and
  /// the median step lies in [kShortestSamplePeriod, kLongestSamplePeriod].
  void validate() const;
};

/// For a median step of t outside [kShortestSamplePeriod, kLongestSamplePeriod]: the sentence that says
/// which time unit would make it a usable period (t in ns, µs or ms: ROS logs stamp nanoseconds), or "".
std::string time_unit_hint(double median_step);

}  // namespace manipid

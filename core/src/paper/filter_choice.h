// filter_choice.h — internal: the differential-filter settings for input-error, given or
// chosen from the data ("auto"), and a measurement-noise estimate for q.
#pragma once

#include "manipid/core/paper/identification.h"
#include "manipid/core/paper/input_error.h"

#include <optional>

#include <vector>

namespace manipid::detail {

/// The grid "auto" searches (half-lengths; bands in rad/sample).
inline const std::vector<int> kAutoHalfLengths = {100, 200, 400};
inline const std::vector<double> kAutoBands = {0.1, 0.15, 0.2, 0.3, 0.4, 0.6, 0.8, 1.2, 1.6, 2.4};

/// The yardstick "auto" measures candidates against on noisy data: parallel filtering. q goes
/// through a wide band (kYardstickWide: flat over any closed-loop motion, so the nonlinear
/// regressor is not bent, but its derivatives noisy), the regressor is formed at every sample,
/// and then its columns and τ go through the same narrow low-pass (kYardstickNarrow). Filtering
/// both sides alike is linear, so the narrow band removes the noise without biasing the fit.
/// On the paper's noisy case its estimate is within 0.2 % (identifiable parameters).
struct YardstickFilter {
  int half_length;
  double band;
};
inline constexpr YardstickFilter kYardstickWide{100, 1.2};
inline constexpr YardstickFilter kYardstickNarrow{100, 0.1};

struct FilterChoice {
  FilterSettings settings;
  bool automatic = false;
  double q_noise = 0.0;  ///< estimated standard deviation of the noise on q, rad (largest joint)
  /// The data filtered with `settings` as filter_for_input_error filters them, when the choice
  /// already did (the floor rule filters long-window candidates at every sample); else empty.
  std::optional<FilteredData> filtered;
};

/// Robust estimate of white measurement noise on one signal: the fourth difference of a
/// smooth signal is tiny, of white noise it has variance 70σ²; the median makes it robust.
double estimate_noise(const Eigen::Ref<const Eigen::VectorXd>& signal);

/// Below these the data carry no measurable noise (simulated or computed data); identification.cpp
/// argues the values where it uses the rule to judge the residual.
inline constexpr double kNoiseFreeAngle = 1e-8;   // rad
inline constexpr double kNoiseFreeTorque = 1e-7;  // of each joint's torque RMS

/// The white noise on each measured signal (estimate_noise), estimated once per identification
/// and read by the filter choice and the residual's assessment.
struct NoiseLevels {
  Eigen::VectorXd q;        ///< rad, per joint
  Eigen::VectorXd tau;      ///< per joint; empty when the data have no τ columns
  Eigen::VectorXd tau_rms;  ///< each joint's τ RMS; empty likewise
  /// No measurable noise on q, nor on τ when the torque is the measured one.
  bool noise_free(bool torque_measured) const;
};
NoiseLevels estimate_noise_levels(const Trajectory& data);

/// Given settings pass through; a zero band or half-length is chosen from the data, by what
/// each candidate does to the estimate. On noisy data (q or measured τ noise above the
/// noise-free thresholds) every candidate's parameters are fitted (Gauss–Newton on its
/// filtered rows, every 16th sample) and compared with the yardstick's: the candidate whose
/// largest relative difference over the parameters the data determine alone is smallest wins.
/// (The lowest least-squares floor J*, the rule before, lets narrow bands win on noisy data —
/// they remove τ noise from the floor while bending the regressor, which is nonlinear in q.)
/// On noise-free data the floor J* measures the filter's distortion alone, and the lowest wins.
FilterChoice choose_filter(const RobotModel& model, const Trajectory& data, const NoiseLevels& noise,
                           const IdentificationOptions& options, bool use_reference);

}  // namespace manipid::detail

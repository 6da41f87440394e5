// filter_choice.h — internal: the differential-filter settings for input-error, given or
// chosen from the data ("auto"), and a measurement-noise estimate for q.
#pragma once

#include "manipid/core/identification.h"

#include <vector>

namespace manipid::detail {

/// The grid "auto" searches (half-lengths; bands in rad/sample).
inline const std::vector<int> kAutoHalfLengths = {100, 200, 400};
inline const std::vector<double> kAutoBands = {0.1, 0.15, 0.2, 0.3, 0.4, 0.6, 0.8, 1.2, 1.6, 2.4};

struct FilterChoice {
  FilterSettings settings;
  bool automatic = false;
  double q_noise = 0.0;  ///< estimated standard deviation of the noise on q, rad (largest joint)
};

/// Robust estimate of white measurement noise on one signal: the fourth difference of a
/// smooth signal is tiny, of white noise it has variance 70σ²; the median makes it robust.
double estimate_noise(const Eigen::Ref<const Eigen::VectorXd>& signal);

/// Given settings pass through; a zero band or half-length is chosen from the data: the
/// candidate with the lowest least-squares floor J* (see filter_choice.cpp).
FilterChoice choose_filter(const RobotModel& model, const Trajectory& data, const IdentificationOptions& options,
                           bool use_reference);

}  // namespace manipid::detail

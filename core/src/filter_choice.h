// filter_choice.h — internal: the differential-filter settings for input-error, given or
// chosen from the data ("auto"), and a measurement-noise estimate for q.
#pragma once

#include "manipid/core/identification.h"

namespace manipid::detail {

struct FilterChoice {
  FilterSettings settings;
  bool automatic = false;
  double q_noise = 0.0;  ///< estimated standard deviation of the noise on q, rad (largest joint)
};

/// Robust estimate of white measurement noise on one signal: the fourth difference of a
/// smooth signal is tiny, of white noise it has variance 70σ²; the median makes it robust.
double estimate_noise(const Eigen::Ref<const Eigen::VectorXd>& signal);

FilterChoice choose_filter(const RobotModel& model, const Trajectory& data, const IdentificationOptions& options,
                           bool use_reference);

}  // namespace manipid::detail

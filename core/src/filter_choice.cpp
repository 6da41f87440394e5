// filter_choice.cpp — filter settings for input-error (filter_choice.h).
#include "filter_choice.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace manipid::detail {

double estimate_noise(const Eigen::Ref<const Eigen::VectorXd>& signal) {
  const Eigen::Index n = signal.size();
  if (n < 5) return 0.0;
  std::vector<double> magnitudes(n - 4);
  for (Eigen::Index i = 2; i < n - 2; ++i) {
    magnitudes[i - 2] = std::abs(signal[i + 2] - 4 * signal[i + 1] + 6 * signal[i] - 4 * signal[i - 1] + signal[i - 2]);
  }
  auto middle = magnitudes.begin() + magnitudes.size() / 2;
  std::nth_element(magnitudes.begin(), middle, magnitudes.end());
  return 1.4826 * *middle / std::sqrt(70.0);
}

FilterChoice choose_filter(const RobotModel& model, const Trajectory& data, const IdentificationOptions& options,
                           bool use_reference) {
  (void)model;
  (void)use_reference;
  FilterChoice choice;
  for (int j = 0; j < data.joint_count(); ++j) choice.q_noise = std::max(choice.q_noise, estimate_noise(data.q.col(j)));
  choice.settings.dt = data.dt();
  choice.automatic = options.band <= 0.0 || options.half_length <= 0;
  choice.settings.band = options.band > 0.0 ? options.band : 0.2;
  choice.settings.half_length = options.half_length > 0 ? options.half_length : 100;
  return choice;
}

}  // namespace manipid::detail

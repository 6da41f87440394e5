// filter_choice.cpp — filter settings for input-error (filter_choice.h).
#include "filter_choice.h"

#include "manipid/core/input_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
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

namespace {

// J*: the cost no parameter value can remove (the least-squares floor over all products β),
// on every `stride`-th filtered sample. It measures how far the filtered data are from any
// instance of the model: filter distortion of the nonlinear dynamics (a band too narrow for
// the motion) plus noise (a band too wide for the derivatives of noisy q).
double floor_for(const RobotModel& model, const Trajectory& data, const FilterSettings& settings, bool use_reference,
                 const std::optional<PdController>& controller, int stride) {
  // Filter only the outputs kept (every stride-th): direct dot products with the taps.
  const auto filter = cached_filter(settings);
  const int outputs = filter->output_length(data.samples());
  const int M = settings.half_length;
  const int rows = (outputs + stride - 1) / stride;
  const int n = data.joint_count();
  FilteredData thin;
  thin.filter = settings;
  thin.q.resize(rows, n);
  thin.qd.resize(rows, n);
  thin.qdd.resize(rows, n);
  thin.tau.resize(rows, n);
  const Eigen::VectorXd& c0 = filter->coefficients(FilterOrder::lowpass);
  const Eigen::VectorXd& c1 = filter->coefficients(FilterOrder::derivative1);
  const Eigen::VectorXd& c2 = filter->coefficients(FilterOrder::derivative2);
  for (int j = 0; j < n; ++j) {
    for (int r = 0; r < rows; ++r) {
      const auto window = data.q.col(j).segment(static_cast<Eigen::Index>(r) * stride, 2 * M + 1);
      thin.q(r, j) = c0.dot(window);
      thin.qd(r, j) = c1.dot(window);
      thin.qdd(r, j) = c2.dot(window);
      if (use_reference) {
        const double reference = c0.dot(data.ref.col(j).segment(static_cast<Eigen::Index>(r) * stride, 2 * M + 1));
        thin.tau(r, j) = controller->kp[j] * (reference - thin.q(r, j)) - controller->kd[j] * thin.qd(r, j);
      } else {
        thin.tau(r, j) = c0.dot(data.tau.col(j).segment(static_cast<Eigen::Index>(r) * stride, 2 * M + 1));
      }
    }
  }
  return InputErrorCost(model, thin).floor();
}

}  // namespace

FilterChoice choose_filter(const RobotModel& model, const Trajectory& data, const IdentificationOptions& options,
                           bool use_reference) {
  FilterChoice choice;
  for (int j = 0; j < data.joint_count(); ++j) choice.q_noise = std::max(choice.q_noise, estimate_noise(data.q.col(j)));
  choice.settings.dt = data.dt();
  choice.settings.half_length = options.half_length;
  choice.settings.band = options.band;
  choice.automatic = options.band <= 0.0 || options.half_length <= 0;
  if (!choice.automatic) return choice;

  // Candidates: the given value where one is given, else a grid. Longer windows flatten the
  // passband (the Harris window's transition is about 4π/M wide) but cost samples at both ends.
  std::vector<int> lengths = options.half_length > 0 ? std::vector<int>{options.half_length} : kAutoHalfLengths;
  std::vector<double> bands = options.band > 0.0 ? std::vector<double>{options.band} : kAutoBands;
  double best = std::numeric_limits<double>::infinity();
  for (int length : lengths) {
    if (data.samples() < 4 * (2 * length + 1)) continue;  // keep most of the data
    for (double band : bands) {
      const FilterSettings candidate{length, band, data.dt()};
      const double value = floor_for(model, data, candidate, use_reference, options.controller, 16);
      if (value < best) {
        best = value;
        choice.settings = candidate;
      }
    }
  }
  if (!std::isfinite(best)) {
    // Too few samples for any candidate window: the shortest that fits, paper's band otherwise.
    choice.settings.half_length = options.half_length > 0 ? options.half_length : std::max(2, (data.samples() - 2) / 8);
    choice.settings.band = options.band > 0.0 ? options.band : 0.2;
  }
  return choice;
}

}  // namespace manipid::detail

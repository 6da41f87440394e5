// output_error.cpp — closed-loop simulation as a cost (output_error.h).
#include "manipid/core/paper/output_error.h"

#include <cmath>
#include <limits>
#include <string>

namespace manipid {

OutputErrorCost::OutputErrorCost(const RobotModel& model, const Trajectory& data, const PdController& controller,
                                 double relative_tolerance)
    : model_(model), data_(data), controller_(controller) {
  const int n = model.joint_count();
  if (data.joint_count() != n) {
    throw InputError("q", "the data has " + std::to_string(data.joint_count()) + " joints, the model " + std::to_string(n));
  }
  if (!data.has_reference()) throw InputError("ref", "output-error needs the reference: the data has no ref columns");
  if (controller.kp.size() != n || controller.kd.size() != n) {
    throw InputError("kp", "kp and kd need " + std::to_string(n) + " entries, one per joint");
  }
  reference_.t0 = 0.0;  // simulated time starts at the first sample
  reference_.dt = data.dt();
  reference_.values = data.ref;
  options_.dt = data.dt();
  options_.duration = data.t[data.samples() - 1] - data.t[0];
  options_.relative_tolerance = relative_tolerance;
  options_.absolute_tolerance = relative_tolerance;
  options_.q0 = data.q.row(0).transpose();
  options_.qd0 = Eigen::VectorXd::Zero(n);
}

double OutputErrorCost::evaluate(const Parameters& parameters, Eigen::VectorXd* residual,
                                 const Eigen::VectorXd* initial_angles) const {
  ++simulations_;
  Trajectory simulated;
  try {
    if (initial_angles) {
      SimulationOptions options = options_;
      options.q0 = *initial_angles;
      simulated = simulate_closed_loop(model_, parameters, controller_, reference_, options);
    } else {
      simulated = simulate_closed_loop(model_, parameters, controller_, reference_, options_);
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception&) {
    // A candidate far from the truth can make the closed loop blow up: an infinite cost
    // steers the optimiser away instead of ending the run.
    if (residual) residual->setConstant(residual_count(), std::numeric_limits<double>::infinity());
    return std::numeric_limits<double>::infinity();
  }
  const int samples = std::min(simulated.samples(), data_.samples());
  const Eigen::MatrixXd difference = simulated.q.topRows(samples) - data_.q.topRows(samples);
  if (residual) *residual = Eigen::Map<const Eigen::VectorXd>(difference.data(), difference.size());
  const double cost = difference.colwise().squaredNorm().sum() / samples;
  return std::isfinite(cost) ? cost : std::numeric_limits<double>::infinity();
}

}  // namespace manipid

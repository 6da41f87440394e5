// output_error.h — the output-error cost: simulate the closed loop for a candidate θ with
// the recorded reference and the controller gains, and compare simulated and measured q.
//
//     J_out(θ) = Σ_j mean_t (q̂_j(t; θ) − q_j(t))²   (rad²)
//
// One evaluation is one closed-loop simulation, which is why the paper prefers input-error.
// Unlike input-error it is unbiased under measurement noise on q (the noise stays in the
// residual instead of entering the regressor), so it finishes the two-stage method.
#pragma once

#include "manipid/core/paper/model.h"
#include "manipid/core/paper/simulation.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <atomic>

namespace manipid {

class OutputErrorCost {
 public:
  /// `data` needs ref columns. The simulation starts at rest from the first measured q unless
  /// an initial angle is given to evaluate() (two-stage estimates it alongside θ, because one
  /// noisy first sample would otherwise bias the estimates through the start transient).
  OutputErrorCost(const RobotModel& model, const Trajectory& data, const PdController& controller,
                  double relative_tolerance = 1e-9);

  /// J_out(θ); with `residual`, also q̂ − q stacked joint after joint (samples·n entries).
  double evaluate(const Parameters& parameters, Eigen::VectorXd* residual = nullptr,
                  const Eigen::VectorXd* initial_angles = nullptr) const;
  /// The measured first sample (the default start), rad.
  Eigen::VectorXd measured_start() const { return options_.q0; }

  long simulations() const { return simulations_.load(); }
  long residual_count() const { return static_cast<long>(data_.samples()) * data_.joint_count(); }

 private:
  RobotModel model_;
  Trajectory data_;
  PdController controller_;
  SampledReference reference_;
  SimulationOptions options_;
  mutable std::atomic<long> simulations_{0};
};

}  // namespace manipid

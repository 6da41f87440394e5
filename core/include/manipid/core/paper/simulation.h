// simulation.h — closed-loop simulation of the manipulator under PD control, and the
// measurement effects (noise, encoder quantisation) that make simulated data realistic.
//
// The controller is the paper's, joint by joint: τ_i = Kp_i (r_i(t) − q_i) − Kd_i q̇_i.
// Integration uses Boost.Odeint's adaptive Dormand–Prince 5(4) stepper with dense output,
// so samples every Δ come from the interpolant and do not force the step size.
#pragma once

#include "manipid/core/paper/model.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace manipid {

struct PdController {
  Eigen::VectorXd kp;  ///< N·m/rad, one per joint
  Eigen::VectorXd kd;  ///< N·m·s/rad, one per joint
};

/// A reference sampled every dt from t0, interpolated between samples by a C¹ cubic
/// (Hermite with central-difference slopes); held constant outside the samples.
struct SampledReference {
  double t0 = 0.0;
  double dt = 0.001;
  Eigen::MatrixXd values;  ///< samples × joints, rad

  int joint_count() const { return static_cast<int>(values.cols()); }
  void evaluate(double t, Eigen::Ref<Eigen::VectorXd> r) const;
  Eigen::VectorXd evaluate(double t) const;
};

/// Delayed steps, one per joint, pre-filtered as the paper does: the step signal is sampled
/// every dt on [0, duration], low-passed with the order-0 differential filter (M, Ωg), and
/// the valid output re-indexed to start at t = 0 — which moves each step earlier by M·dt.
struct StepReferenceSpec {
  std::vector<double> step_times;   ///< s, one per joint
  std::vector<double> amplitudes;   ///< rad, one per joint
  double duration = 10.0;           ///< length of the raw step signal, s
  double dt = 0.001;                ///< s
  int half_length = 100;            ///< M of the pre-filter
  double band = 0.025;              ///< Ωg of the pre-filter, rad/sample
};
SampledReference make_step_reference(const StepReferenceSpec& spec);

struct SimulationOptions {
  double duration = 9.7;              ///< s; samples at 0, dt, ..., duration (both ends)
  double dt = 0.001;                  ///< output sample period, s
  double relative_tolerance = 1e-8;   ///< of the adaptive integrator
  /// Of the adaptive integrator (rad, rad/s). 1e-8 keeps q within 4e-8 rad of a 1e-13 run on
  /// the paper's case; tighter mostly resolves nearly settled rates for nothing.
  double absolute_tolerance = 1e-8;
  Eigen::VectorXd q0;                 ///< initial angles (default zeros), rad
  Eigen::VectorXd qd0;                ///< initial rates (default zeros), rad/s
  /// Asked after every accepted integrator step (and before the first); when it returns true
  /// the run ends at once with SimulationStopped. Empty = never stop. This is how a caller
  /// makes a long simulation answer cancel, a time limit or shutdown.
  std::function<bool()> should_stop;
};

/// Thrown by simulate_closed_loop when options.should_stop asked it to end: not a numerical
/// failure (deliberately not a std::runtime_error), the caller decides what the stop meant.
class SimulationStopped : public std::exception {
 public:
  SimulationStopped(double t, long steps)
      : t_(t), steps_(steps), message_("simulation: stopped on request at t = " + std::to_string(t) + " s") {}
  const char* what() const noexcept override { return message_.c_str(); }
  double time() const { return t_; }   ///< simulated time reached, s
  long steps() const { return steps_; }  ///< accepted integrator steps taken

 private:
  double t_;
  long steps_;
  std::string message_;
};

/// Measurement effects applied to a simulated trajectory, reproducible for a given seed.
struct MeasurementNoise {
  double q_sigma = 0.0;       ///< standard deviation of Gaussian noise on q, rad
  double tau_sigma = 0.0;     ///< standard deviation of Gaussian noise on τ, N·m
  /// More noise on τ, as a fraction of each joint's torque standard deviation (0.01 = 1 %);
  /// the two parts add in quadrature.
  double tau_relative_sigma = 0.0;
  int quantize_bits = 0;      ///< encoder resolution 2π / 2^bits on q; 0 = none
  std::uint64_t seed = 1;

  bool any() const { return q_sigma > 0 || tau_sigma > 0 || tau_relative_sigma > 0 || quantize_bits > 0; }
};

struct SimulationSummary {
  long steps = 0;            ///< accepted integrator steps
  long rhs_evaluations = 0;  ///< forward-dynamics calls
  double wall_seconds = 0.0;
};

/// Simulates the closed loop; returns t, q, τ (the controller's output) and ref at every
/// sample. Throws InputError on inconsistent sizes or settings, and std::runtime_error when
/// the motion diverges (|q| > 1e6 rad, a non-finite state, or the step limit) — what a
/// far-off parameter guess can do; output-error turns that into an infinite cost. Throws
/// SimulationStopped when options.should_stop returns true.
Trajectory simulate_closed_loop(const RobotModel& model, const Parameters& parameters,
                                const PdController& controller, const SampledReference& reference,
                                const SimulationOptions& options, SimulationSummary* summary = nullptr);

/// Adds noise to q and τ, then quantises q (noise first: the encoder reads the noisy angle).
void apply_measurement_noise(Trajectory& trajectory, const MeasurementNoise& noise);

}  // namespace manipid

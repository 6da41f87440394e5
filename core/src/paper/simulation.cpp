// simulation.cpp — the paper's experiment: a pre-filtered step reference, the manipulator
// under joint-wise PD control integrated with Boost.Odeint's dense-output Dormand–Prince
// 5(4), and the measurement effects (noise, encoder quantisation) applied afterwards.
#include "manipid/core/paper/simulation.h"

#include "manipid/core/paper/dynamics.h"
#include "manipid/core/signal/filters.h"
#include "numbers.h"

#include <boost/numeric/odeint/stepper/controlled_runge_kutta.hpp>
#include <boost/numeric/odeint/stepper/dense_output_runge_kutta.hpp>
#include <boost/numeric/odeint/stepper/generation.hpp>
#include <boost/numeric/odeint/stepper/runge_kutta_dopri5.hpp>
#include <boost/numeric/odeint/util/odeint_error.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace manipid {
namespace {

using manipid::detail::message_number;

namespace odeint = boost::numeric::odeint;

// A std::vector state with odeint's default range algebra. Measured on 8 states, the
// integrator's own cost (stage sums, error norm, dense output) is ≈ 75 ns per RHS call
// with std::vector and ≈ 85 ns with Eigen::VectorXd and vector_space_algebra, both small
// against ≈ 1 µs of forward dynamics. Buffers are sized once, at initialize().
using State = std::vector<double>;

// Longest series the library will produce (per joint): 10⁷ samples are 2.8 hours at 1 ms.
constexpr double max_samples = 1e7;
// Guard against a run that never finishes (a candidate model so stiff or so fast that the
// steps collapse): at most this many accepted steps per output sample. The paper needs 0.4.
constexpr long max_steps_per_sample = 100;

void require_finite_vector(const std::string& field, const Eigen::VectorXd& values) {
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      throw InputError(field, field + std::to_string(i + 1) + " is not finite");
    }
  }
}

void require_positive(const std::string& field, double value) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw InputError(field, field + " must be positive and finite, got " + message_number(value));
  }
}

// Number of sample intervals in `duration` at period `dt`, both validated.
long interval_count(const std::string& duration_field, double duration, double dt) {
  const double intervals = std::round(duration / dt);
  if (intervals < 1.0) {
    throw InputError(duration_field, duration_field + " (" + message_number(duration) +
                                         " s) must be at least one sample period dt (" + message_number(dt) + " s)");
  }
  if (intervals + 1.0 > max_samples) {
    throw InputError(duration_field, duration_field + " / dt gives " + message_number(intervals + 1.0) +
                                         " samples; at most " + message_number(max_samples) + " are allowed");
  }
  return static_cast<long>(intervals);
}

// Cubic Hermite basis on u ∈ [0, 1) for values y0, y1 and slopes m0, m1 (per sample).
inline double hermite(double u, double y0, double y1, double m0, double m1) {
  const double u2 = u * u;
  const double u3 = u2 * u;
  return (2.0 * u3 - 3.0 * u2 + 1.0) * y0 + (u3 - 2.0 * u2 + u) * m0 + (3.0 * u2 - 2.0 * u3) * y1 +
         (u3 - u2) * m1;
}

void check_controller(const PdController& controller, int joints) {
  const std::pair<const char*, const Eigen::VectorXd*> gains[] = {{"kp", &controller.kp},
                                                                  {"kd", &controller.kd}};
  for (const auto& [field, gain] : gains) {
    if (gain->size() != joints) {
      throw InputError(field, std::string(field) + " has " + std::to_string(gain->size()) +
                                  " entries but the model has " + std::to_string(joints) + " joints");
    }
    for (Eigen::Index i = 0; i < gain->size(); ++i) {
      if (!std::isfinite((*gain)[i]) || (*gain)[i] < 0.0) {
        throw InputError(field, std::string(field) + std::to_string(i + 1) +
                                    " must be finite and non-negative, got " + message_number((*gain)[i]));
      }
    }
  }
}

void check_reference(const SampledReference& reference, int joints) {
  if (reference.joint_count() != joints) {
    throw InputError("reference", "the reference has " + std::to_string(reference.joint_count()) +
                                      " joints but the model has " + std::to_string(joints));
  }
  if (reference.values.rows() < 1) throw InputError("reference", "the reference has no samples");
  if (!std::isfinite(reference.t0)) throw InputError("reference", "the reference's t0 is not finite");
  if (!std::isfinite(reference.dt) || reference.dt <= 0.0) {
    throw InputError("reference", "the reference's dt must be positive, got " + message_number(reference.dt));
  }
  if (!reference.values.allFinite()) throw InputError("reference", "the reference has non-finite values");
}

Eigen::VectorXd initial_vector(const std::string& field, const Eigen::VectorXd& given, int joints) {
  if (given.size() == 0) return Eigen::VectorXd::Zero(joints);
  if (given.size() != joints) {
    throw InputError(field, field + " has " + std::to_string(given.size()) + " entries but the model has " +
                                std::to_string(joints) + " joints (or leave it empty for zeros)");
  }
  require_finite_vector(field, given);
  return given;
}

// Everything the right-hand side needs, built once per simulation. Odeint copies the system
// functor at every step, so the functor itself only holds a pointer to this.
struct ClosedLoop {
  const RobotModel& model;
  const Parameters& parameters;
  const PdController& controller;
  const SampledReference& reference;
  int joints;
  DynamicsWorkspace workspace;
  Eigen::VectorXd r, tau;  // scratch, sized once
  long rhs_evaluations = 0;

  // τ = Kp∘(r − q) − Kd∘q̇ into `tau` (r must already hold r(t)).
  template <class Q, class Qd>
  void control(const Q& q, const Qd& qd) {
    tau = controller.kp.cwiseProduct(r - q) - controller.kd.cwiseProduct(qd);
  }
};

struct ClosedLoopSystem {
  ClosedLoop* loop;

  void operator()(const State& x, State& dxdt, double t) const {
    const int n = loop->joints;
    const Eigen::Map<const Eigen::VectorXd> q(x.data(), n), qd(x.data() + n, n);
    Eigen::Map<Eigen::VectorXd> qd_out(dxdt.data(), n), qdd(dxdt.data() + n, n);
    loop->reference.evaluate(t, loop->r);
    loop->control(q, qd);
    qd_out = qd;
    forward_dynamics(loop->model, loop->parameters, loop->workspace, q, qd, loop->tau, qdd);
    ++loop->rhs_evaluations;
  }
};

// Beyond this many radians a joint has certainly run away: the angle then carries fewer
// digits than the tolerances ask for, and rounding noise in sin/cos times huge rates stalls
// the step control long before the state overflows (seen: 1e6 steps at |q| ≈ 1e19).
constexpr double runaway_angle = 1e6;

// The first joint (0-based) whose state is not finite or has run away, or -1.
int diverged_joint(const State& x, int joints) {
  for (int i = 0; i < joints; ++i) {
    if (!(std::abs(x[i]) <= runaway_angle) || !std::isfinite(x[joints + i])) return i;
  }
  return -1;
}

}  // namespace

void SampledReference::evaluate(double t, Eigen::Ref<Eigen::VectorXd> r) const {
  const Eigen::Index count = values.rows();
  if (count == 0 || r.size() != values.cols()) {
    throw InputError("reference", "evaluate: the reference has " + std::to_string(count) +
                                      " samples and " + std::to_string(values.cols()) +
                                      " joints, the output has " + std::to_string(r.size()) + " entries");
  }
  const double position = (t - t0) / dt;  // in samples
  // Held constant outside the samples (also catches a NaN t, which then gives the first value).
  if (!(position > 0.0)) {
    r = values.row(0).transpose();
    return;
  }
  if (position >= static_cast<double>(count - 1)) {
    r = values.row(count - 1).transpose();
    return;
  }
  const Eigen::Index k = static_cast<Eigen::Index>(position);  // interval [k, k+1], count ≥ 2 here
  const double u = position - static_cast<double>(k);
  const bool first = k == 0;
  const bool last = k + 2 == count;
  for (Eigen::Index j = 0; j < values.cols(); ++j) {
    const double* y = values.col(j).data();
    // Slopes in units of value per sample: central differences, one-sided at the ends.
    const double m0 = first ? y[1] - y[0] : 0.5 * (y[k + 1] - y[k - 1]);
    const double m1 = last ? y[k + 1] - y[k] : 0.5 * (y[k + 2] - y[k]);
    r[j] = hermite(u, y[k], y[k + 1], m0, m1);
  }
}

Eigen::VectorXd SampledReference::evaluate(double t) const {
  Eigen::VectorXd r(values.cols());
  evaluate(t, r);
  return r;
}

SampledReference make_step_reference(const StepReferenceSpec& spec) {
  if (spec.step_times.empty()) throw InputError("step_times", "step_times needs one entry per joint");
  if (spec.amplitudes.size() != spec.step_times.size()) {
    throw InputError("amplitudes", "amplitudes has " + std::to_string(spec.amplitudes.size()) +
                                       " entries but step_times has " + std::to_string(spec.step_times.size()));
  }
  for (std::size_t j = 0; j < spec.step_times.size(); ++j) {
    if (!std::isfinite(spec.step_times[j])) {
      throw InputError("step_times", "step time " + std::to_string(j + 1) + " is not finite");
    }
    if (!std::isfinite(spec.amplitudes[j])) {
      throw InputError("amplitudes", "amplitude " + std::to_string(j + 1) + " is not finite");
    }
  }
  require_positive("dt", spec.dt);
  require_positive("duration", spec.duration);
  const FilterSettings settings{spec.half_length, spec.band, spec.dt};
  settings.validate();
  const long intervals = interval_count("duration", spec.duration, spec.dt);
  const long raw_samples = intervals + 1;
  const auto filter = cached_filter(settings);
  const int output_samples = filter->output_length(static_cast<int>(raw_samples));
  if (output_samples < 2) {
    throw InputError("duration", "the pre-filter (half_length " + std::to_string(spec.half_length) +
                                     ") needs more than " + std::to_string(DifferentialFilter::min_input_samples(spec.half_length)) +
                                     " samples; duration / dt gives " + std::to_string(raw_samples));
  }

  const int joints = static_cast<int>(spec.step_times.size());
  SampledReference reference;
  reference.t0 = 0.0;
  reference.dt = spec.dt;
  reference.values.resize(output_samples, joints);
  Eigen::VectorXd raw(raw_samples);
  for (int j = 0; j < joints; ++j) {
    for (long i = 0; i < raw_samples; ++i) {
      // Mathematica's UnitStep(0) = 1: the step is already on at t = step_time.
      raw[i] = static_cast<double>(i) * spec.dt - spec.step_times[j] >= 0.0 ? spec.amplitudes[j] : 0.0;
    }
    // Output j is centred on raw sample M + j; re-indexing it to t = j·dt (the paper's tp1)
    // moves the steps M·dt earlier. The direct sum keeps the reference exactly 0 before the
    // step, so a run starts exactly at rest (the FFT would leave ~1e-18 rad of rounding there).
    filter->apply_direct(FilterOrder::lowpass, raw, reference.values.col(j));
  }
  return reference;
}

Trajectory simulate_closed_loop(const RobotModel& model, const Parameters& parameters,
                                const PdController& controller, const SampledReference& reference,
                                const SimulationOptions& options, SimulationSummary* summary) {
  const auto started = std::chrono::steady_clock::now();
  const int n = model.joint_count();
  if (n < 1) throw InputError("model", "the model has no joints");
  check_parameters(model, parameters);
  check_controller(controller, n);
  check_reference(reference, n);
  require_positive("dt", options.dt);
  require_positive("duration", options.duration);
  require_positive("absolute_tolerance", options.absolute_tolerance);
  // Below ~1e-14 the error target is under double rounding and the steps would collapse.
  if (!std::isfinite(options.relative_tolerance) || options.relative_tolerance < 1e-14 ||
      options.relative_tolerance >= 1.0) {
    throw InputError("relative_tolerance", "relative_tolerance must lie in [1e-14, 1), got " +
                                               message_number(options.relative_tolerance));
  }
  const Eigen::VectorXd q0 = initial_vector("q0", options.q0, n);
  const Eigen::VectorXd qd0 = initial_vector("qd0", options.qd0, n);
  const long intervals = interval_count("duration", options.duration, options.dt);
  const Eigen::Index samples = intervals + 1;

  ClosedLoop loop{model, parameters, controller, reference, n, DynamicsWorkspace(model),
                  Eigen::VectorXd(n), Eigen::VectorXd(n)};
  const ClosedLoopSystem system{&loop};

  State x(2 * static_cast<std::size_t>(n));
  Eigen::Map<Eigen::VectorXd>(x.data(), n) = q0;
  Eigen::Map<Eigen::VectorXd>(x.data() + n, n) = qd0;

  // Steps of at most 10 reference samples: the stages of a step are then at most 5 samples
  // apart, so no reference feature that wide can fall between them unseen (e.g. a short
  // pulse while the arm is at rest and the steps have grown). The paper's run never comes
  // near it (its longest step is 6.9 ms), so this costs nothing there.
  const double max_step = 10.0 * reference.dt;
  auto stepper = odeint::make_dense_output(options.absolute_tolerance, options.relative_tolerance, max_step,
                                           odeint::runge_kutta_dopri5<State>());
  // A first guess only: the controller rejects and shrinks it within a few tries if needed.
  stepper.initialize(x, 0.0, std::min(0.1 * options.dt, max_step));

  Trajectory trajectory;
  trajectory.t.resize(samples);
  trajectory.q.resize(samples, n);
  trajectory.tau.resize(samples, n);
  trajectory.ref.resize(samples, n);

  // Numerical failures are std::runtime_error, not InputError: the inputs were consistent,
  // the dynamics were not integrable (e.g. a candidate in an identification blew up).
  const long max_steps = std::max<long>(100'000, max_steps_per_sample * samples);
  long steps = 0;
  const auto stop_requested = [&options] { return options.should_stop && options.should_stop(); };
  if (stop_requested()) throw SimulationStopped(0.0, 0);
  for (Eigen::Index i = 0; i < samples; ++i) {
    const double t = static_cast<double>(i) * options.dt;
    while (stepper.current_time() < t) {
      try {
        stepper.do_step(system);
      } catch (const odeint::odeint_error& error) {
        throw std::runtime_error("simulation: the integrator failed near t = " +
                                 message_number(stepper.current_time()) + " s (" + error.what() + ")");
      }
      ++steps;
      if (const int joint = diverged_joint(stepper.current_state(), n); joint >= 0) {
        throw std::runtime_error("simulation: the closed loop diverged near t = " +
                                 message_number(stepper.current_time()) + " s (joint " + std::to_string(joint + 1) +
                                 " at q = " + message_number(stepper.current_state()[joint]) + " rad)");
      }
      if (steps > max_steps || !(stepper.current_time() > stepper.previous_time())) {
        throw std::runtime_error("simulation: the integrator could not get past t = " +
                                 message_number(stepper.current_time()) + " s in " + std::to_string(steps) +
                                 " steps (tolerances too tight for this model?)");
      }
      if (stop_requested()) throw SimulationStopped(stepper.current_time(), steps);
    }
    // The state at t from the stepper's continuous extension (exact x0 at the start).
    if (i > 0) stepper.calc_state(t, x);
    const Eigen::Map<const Eigen::VectorXd> q(x.data(), n), qd(x.data() + n, n);
    reference.evaluate(t, loop.r);
    loop.control(q, qd);
    trajectory.t[i] = t;
    trajectory.q.row(i) = q.transpose();
    trajectory.tau.row(i) = loop.tau.transpose();
    trajectory.ref.row(i) = loop.r.transpose();
  }

  if (summary != nullptr) {
    summary->steps = steps;
    summary->rhs_evaluations = loop.rhs_evaluations;
    summary->wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  }
  return trajectory;
}

void apply_measurement_noise(Trajectory& trajectory, const MeasurementNoise& noise) {
  if (!std::isfinite(noise.q_sigma) || noise.q_sigma < 0.0) {
    throw InputError("q_sigma", "q_sigma must be finite and non-negative, got " + message_number(noise.q_sigma));
  }
  if (!std::isfinite(noise.tau_sigma) || noise.tau_sigma < 0.0) {
    throw InputError("tau_sigma", "tau_sigma must be finite and non-negative, got " + message_number(noise.tau_sigma));
  }
  if (!std::isfinite(noise.tau_relative_sigma) || noise.tau_relative_sigma < 0.0) {
    throw InputError("tau_relative_sigma",
                     "tau_relative_sigma must be finite and non-negative, got " + message_number(noise.tau_relative_sigma));
  }
  if (noise.quantize_bits < 0 || noise.quantize_bits > 62) {
    throw InputError("quantize_bits", "quantize_bits must lie in 0..62 (0 = no quantisation), got " +
                                          std::to_string(noise.quantize_bits));
  }
  // One generator for the whole trajectory, drawn in a fixed order (q column by column,
  // then τ), so a seed always gives the same data.
  std::mt19937_64 generator(noise.seed);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  double* const q = trajectory.q.data();
  double* const tau = trajectory.tau.data();
  if (noise.q_sigma > 0.0) {
    for (Eigen::Index i = 0; i < trajectory.q.size(); ++i) q[i] += noise.q_sigma * gaussian(generator);
  }
  if (noise.tau_sigma > 0.0 || noise.tau_relative_sigma > 0.0) {
    const Eigen::Index samples = trajectory.tau.rows();
    for (Eigen::Index j = 0; j < trajectory.tau.cols(); ++j) {
      // Each joint's noise: the absolute part plus a fraction of that joint's torque spread.
      const auto column = trajectory.tau.col(j).array();
      const double spread = samples > 0 ? std::sqrt((column - column.mean()).square().mean()) : 0.0;
      const double sigma = std::hypot(noise.tau_sigma, noise.tau_relative_sigma * spread);
      for (Eigen::Index i = 0; i < samples; ++i) tau[j * samples + i] += sigma * gaussian(generator);
    }
  }
  if (noise.quantize_bits > 0) {
    const double resolution = 2.0 * std::numbers::pi / std::ldexp(1.0, noise.quantize_bits);
    for (Eigen::Index i = 0; i < trajectory.q.size(); ++i) q[i] = std::round(q[i] / resolution) * resolution;
  }
}

}  // namespace manipid

// requests_simulation.cpp — simulation requests (requests.h): a preset's closed-loop experiment
// with optional overrides, checked up front so an accepted job can run, and the run itself —
// the same core calls as `manipid simulate`, so equal settings give equal data.
#include "json_fields.h"
#include "manipid/core/signal/filters.h"

#include <cmath>
#include <numbers>

namespace manipid::api {
namespace fields {
namespace {

constexpr double max_duration = 3600.0;  // s: an hour of data is far more than any experiment here

std::string samples_limit_text() { return std::to_string(static_cast<long long>(max_samples)); }

/// Reads "reference": overrides of the preset's step reference.
void read_reference(const Json& value, const std::string& path, int joints, StepReferenceSpec& reference) {
  const ObjectFields object(value, path, {"step_times", "amplitudes", "half_length", "band", "duration"});
  if (const Json* times = object.find("step_times")) {
    reference.step_times = read_joint_numbers(*times, object.path("step_times"), joints, false);
  }
  if (const Json* amplitudes = object.find("amplitudes")) {
    reference.amplitudes = read_joint_numbers(*amplitudes, object.path("amplitudes"), joints, false);
  }
  // The pre-filter is a differential filter: M ≥ 2, like every other (filters.h).
  if (const Json* half_length = object.find("half_length")) {
    reference.half_length = static_cast<int>(read_integer(*half_length, object.path("half_length"), 2, 1'000'000));
  }
  if (const Json* band = object.find("band")) {
    reference.band = read_positive(*band, object.path("band"), std::numbers::pi, " rad/sample");
    validate_band(reference.band, object.path("band"));
  }
  if (const Json* duration = object.find("duration")) {
    reference.duration = read_positive(*duration, object.path("duration"), max_duration, " s");
  }
}

void read_noise(const Json& value, const std::string& path, MeasurementNoise& noise) {
  const ObjectFields object(value, path, {"q_sigma", "tau_sigma", "tau_relative_sigma", "quantize_bits", "seed"});
  if (const Json* sigma = object.find("q_sigma")) noise.q_sigma = read_non_negative(*sigma, object.path("q_sigma"));
  if (const Json* sigma = object.find("tau_sigma")) noise.tau_sigma = read_non_negative(*sigma, object.path("tau_sigma"));
  if (const Json* sigma = object.find("tau_relative_sigma")) {
    noise.tau_relative_sigma = read_non_negative(*sigma, object.path("tau_relative_sigma"));
  }
  if (const Json* bits = object.find("quantize_bits")) {
    noise.quantize_bits = static_cast<int>(read_integer(*bits, object.path("quantize_bits"), 0, 62));
  }
  if (const Json* seed = object.find("seed")) noise.seed = read_unsigned(*seed, object.path("seed"));
}

/// The checks simulate_closed_loop and make_step_reference would make at run time, made now
/// with the request's field names, plus the sample limits that keep memory bounded.
void check_sampling(const ObjectFields& object, const SimulationSpec& spec) {
  const SimulationOptions& simulation = spec.preset.simulation;
  const StepReferenceSpec& reference = spec.preset.reference;
  const double dt = simulation.dt;
  const std::string duration_or_dt = object.has("dt") ? object.path("dt") : object.path("duration");

  const double intervals = std::round(simulation.duration / dt);
  if (intervals < 1.0) {
    throw InputError(duration_or_dt, "duration (" + format_number(simulation.duration) +
                                         " s) must be at least one sample period dt (" + format_number(dt) + " s)");
  }
  if (intervals + 1.0 > max_samples) {
    throw InputError(duration_or_dt, "duration / dt gives " + format_number(intervals + 1.0) + " samples; at most " +
                                         samples_limit_text() + " are allowed");
  }
  // The simulated dataset holds t, q, tau and ref: it must fit the store like an upload.
  limits::check_dataset_size(static_cast<long long>(intervals) + 1, spec.preset.model.joint_count(), 3, duration_or_dt,
                             "duration / dt");

  // The reference is sampled at the same dt over its own duration, then pre-filtered.
  const Json* reference_value = object.find("reference");
  const bool reference_duration_given = reference_value && reference_value->contains("duration");
  const bool reference_half_length_given = reference_value && reference_value->contains("half_length");
  const std::string reference_path = object.path("reference");
  const double reference_intervals = std::round(reference.duration / dt);
  if (reference_intervals + 1.0 > max_samples) {
    const std::string field = object.has("dt") ? object.path("dt") : member_path(reference_path, "duration");
    throw InputError(field, "the reference's duration / dt gives " + format_number(reference_intervals + 1.0) +
                                " samples; at most " + samples_limit_text() + " are allowed");
  }
  const double filtered_samples = reference_intervals + 1.0 - 2.0 * reference.half_length - 1.0;
  if (filtered_samples < 2.0) {
    const std::string field = reference_half_length_given ? member_path(reference_path, "half_length")
                              : reference_duration_given  ? member_path(reference_path, "duration")
                              : object.has("dt")          ? object.path("dt")
                                                          : member_path(reference_path, "half_length");
    throw InputError(field, "the reference pre-filter (half_length " + std::to_string(reference.half_length) +
                                ") needs more than " + std::to_string(DifferentialFilter::min_input_samples(reference.half_length)) +
                                " samples; the reference's duration / dt gives " +
                                format_number(reference_intervals + 1.0));
  }
}

}  // namespace

SimulationSpec read_simulation(const Json& body, const std::string& path) {
  const ObjectFields object(body, path,
                            {"preset", "kinetic_energy", "name", "parameters", "kp", "kd", "reference", "duration",
                             "dt", "relative_tolerance", "absolute_tolerance", "noise"});
  KineticEnergy kinetic_energy = KineticEnergy::complete;
  if (const Json* value = object.find("kinetic_energy")) {
    const std::string field = object.path("kinetic_energy");
    kinetic_energy = parse_kinetic_energy(read_string(*value, field), field);
  }
  const std::string preset_name = object.has("preset") ? read_string(*object.find("preset"), object.path("preset"))
                                                       : std::string("cedro2009");
  SimulationSpec spec;
  try {
    spec.preset = find_preset(preset_name, kinetic_energy);
  } catch (const InputError& error) {
    rethrow_at(error, object.path("preset"));
  }
  Preset& preset = spec.preset;
  const int joints = preset.model.joint_count();
  spec.parameters = preset.true_parameters;

  if (const Json* name = object.find("name")) spec.name = read_label(*name, object.path("name"));
  if (const Json* parameters = object.find("parameters")) {
    // Negative masses or lengths have no physical meaning (and make the mass matrix indefinite).
    Eigen::VectorXd theta = spec.parameters.vector();
    read_parameter_object(*parameters, object.path("parameters"), joints, true,
                          [&](int index, double number, const std::string&) { theta[index] = number; });
    spec.parameters = Parameters::from_vector(theta);
    check_parameter_ranges(spec.parameters, object.path("parameters"));
  }
  if (const Json* kp = object.find("kp")) preset.controller.kp = read_gains(*kp, object.path("kp"), joints);
  if (const Json* kd = object.find("kd")) preset.controller.kd = read_gains(*kd, object.path("kd"), joints);
  if (const Json* reference = object.find("reference")) {
    read_reference(*reference, object.path("reference"), joints, preset.reference);
  }
  if (const Json* duration = object.find("duration")) {
    preset.simulation.duration = read_positive(*duration, object.path("duration"), max_duration, " s");
  }
  if (const Json* dt = object.find("dt")) {
    const double period = read_positive(*dt, object.path("dt"), max_duration, " s");
    preset.simulation.dt = period;
    preset.reference.dt = period;
  }
  if (const Json* tolerance = object.find("relative_tolerance")) {
    // The integrator's own limits (simulation.h): below 1e-14 the steps collapse.
    const std::string field = object.path("relative_tolerance");
    const double value = read_number(*tolerance, field);
    if (!(value >= 1e-14 && value < 1.0)) {
      throw InputError(field, field + " must be in [1e-14, 1), got " + format_number(value));
    }
    preset.simulation.relative_tolerance = value;
  }
  if (const Json* tolerance = object.find("absolute_tolerance")) {
    preset.simulation.absolute_tolerance = read_positive(*tolerance, object.path("absolute_tolerance"));
  }
  if (const Json* noise = object.find("noise")) read_noise(*noise, object.path("noise"), spec.noise);

  check_sampling(object, spec);
  return spec;
}

int simulation_samples(const SimulationSpec& spec) {
  return static_cast<int>(std::round(spec.preset.simulation.duration / spec.preset.simulation.dt)) + 1;
}

}  // namespace fields

SimulationSpec simulation_from_json(const nlohmann::json& body) { return fields::read_simulation(body, ""); }

Trajectory run_simulation(const SimulationSpec& spec, SimulationSummary* summary) {
  const Preset& preset = spec.preset;
  const SampledReference reference = make_step_reference(preset.reference);
  Trajectory trajectory =
      simulate_closed_loop(preset.model, spec.parameters, preset.controller, reference, preset.simulation, summary);
  if (spec.noise.any()) apply_measurement_noise(trajectory, spec.noise);
  return trajectory;
}

}  // namespace manipid::api

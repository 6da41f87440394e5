// requests_identification.cpp — identification requests (requests.h): the options `manipid
// identify` builds from its command line, built from JSON with the same defaults, and the
// checks that need the data (joint count, samples for the filter, tau/ref columns).
#include "json_fields.h"
#include "manipid/core/signal/filters.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace manipid::api {
namespace {

constexpr std::size_t max_dataset_id_length = 64;
constexpr long long max_half_length = 1'000'000;  // the differential filter's limit (filters.cpp)
constexpr double max_seconds_limit = 86'400.0;    // one day
// Samples the filters need (core/src/paper/filter_choice.cpp and identification.cpp): with M = "auto"
// the grid {100, 200, 400} is searched only when the data has 4(2M+1) samples; shorter data
// falls back to M = max(2, (samples - 2) / 8), so "auto" needs no more than 2·2+1 samples.
// Output-error always builds its identifiability structure with M = 100.
constexpr int smallest_automatic_half_length = 2;
constexpr int output_error_structure_half_length = 100;

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

/// The field naming the data: the dataset, or the simulation that will make it.
std::string data_field(const IdentificationSpec& spec) { return spec.simulation ? "simulation" : "dataset_id"; }
std::string data_noun(const IdentificationSpec& spec) { return spec.simulation ? "the simulated data" : "the dataset"; }

void read_free(const fields::Json& value, int joints, std::vector<std::string>& free) {
  if (!value.is_array()) {
    throw InputError("free", "free must be an array of parameter names ([\"m2\", \"l2\", ...]), got " + fields::describe(value));
  }
  if (value.empty()) {
    throw InputError("free", "free is empty: name at least one parameter, or leave free out to estimate all of them");
  }
  const std::string last = std::to_string(joints);
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string path = fields::element_path("free", i);
    const std::string name = fields::read_string(value[i], path);
    if (parameter_index(name, joints) < 0) {
      throw InputError(path, path + " is \"" + name + "\", not a parameter of this robot (m1..m" + last + ", l1..l" +
                                 last + ")");
    }
    if (std::find(free.begin(), free.end(), name) != free.end()) {
      throw InputError(path, path + ": " + name + " is listed twice");
    }
    free.push_back(name);
  }
}

/// Reads "lower" and "upper" into 2n-entry bound vectors (defaults [0, +∞), the core's) and
/// checks each given bound against the other bound and against the initial value.
void read_bounds(const fields::ObjectFields& object, int joints, IdentificationOptions& options) {
  const fields::Json* lower = object.find("lower");
  const fields::Json* upper = object.find("upper");
  if (!lower && !upper) return;  // the core's defaults
  const int count = 2 * joints;
  options.lower = Eigen::VectorXd::Zero(count);
  options.upper = Eigen::VectorXd::Constant(count, fields::infinity);
  std::vector<std::string> lower_fields(static_cast<std::size_t>(count)), upper_fields(static_cast<std::size_t>(count));
  if (lower) {
    fields::read_parameter_object(*lower, "lower", joints, false, [&](int index, double number, const std::string& field) {
      options.lower[index] = number;
      lower_fields[static_cast<std::size_t>(index)] = field;
    });
  }
  if (upper) {
    fields::read_parameter_object(*upper, "upper", joints, false, [&](int index, double number, const std::string& field) {
      options.upper[index] = number;
      upper_fields[static_cast<std::size_t>(index)] = field;
    });
  }
  const std::vector<std::string> names = parameter_names(joints);
  const Eigen::VectorXd initial = options.initial.vector();
  for (int i = 0; i < count; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const std::string interval =
        "[" + fields::format_number(options.lower[i]) + ", " + fields::format_number(options.upper[i]) + "]";
    if (options.lower[i] > options.upper[i]) {
      const std::string& field = !lower_fields[k].empty() ? lower_fields[k] : upper_fields[k];
      throw InputError(field, "the bounds of " + names[k] + " are not an interval: lower " +
                                  fields::format_number(options.lower[i]) + " > upper " +
                                  fields::format_number(options.upper[i]));
    }
    const std::string start = "the initial value of " + names[k] + " (" + fields::format_number(initial[i]) + ")";
    if (initial[i] < options.lower[i]) {
      throw InputError(lower_fields[k], lower_fields[k] + " = " + fields::format_number(options.lower[i]) + " excludes " +
                                            start + "; give initial." + names[k] + " inside " + interval);
    }
    if (initial[i] > options.upper[i]) {
      throw InputError(upper_fields[k], upper_fields[k] + " = " + fields::format_number(options.upper[i]) + " excludes " +
                                            start + "; give initial." + names[k] + " inside " + interval);
    }
  }
}

}  // namespace

IdentificationSpec identification_from_json(const nlohmann::json& body) {
  const fields::ObjectFields object(
      body, "",
      {"dataset_id", "simulation", "preset", "kinetic_energy", "method", "algorithm", "free", "initial", "lower", "upper",
       "kp", "kd", "half_length", "band", "torque_source", "weights", "max_evaluations", "max_seconds",
       "relative_x_tolerance", "relative_f_tolerance", "output_error_iterations", "truth"});
  IdentificationSpec spec;

  // The data: an uploaded dataset, or a simulation to run first.
  const fields::Json* dataset_id = object.find("dataset_id");
  const fields::Json* simulation = object.find("simulation");
  if (dataset_id && simulation) throw InputError("simulation", "give either dataset_id or simulation, not both");
  if (!dataset_id && !simulation) {
    throw InputError("dataset_id", "missing dataset_id: give the data as dataset_id (an uploaded dataset) or "
                                   "simulation (a simulation request to run first)");
  }
  if (dataset_id) {
    spec.dataset_id = fields::read_string(*dataset_id, "dataset_id");
    if (spec.dataset_id.empty()) throw InputError("dataset_id", "dataset_id is empty");
    if (spec.dataset_id.size() > max_dataset_id_length) {
      throw InputError("dataset_id", "dataset_id has " + std::to_string(spec.dataset_id.size()) + " characters, at most " +
                                         std::to_string(max_dataset_id_length) + " are allowed");
    }
  } else {
    spec.simulation = fields::read_simulation(*simulation, "simulation");
  }

  // The model: by default the simulation's robot, else the paper's.
  KineticEnergy kinetic_energy = spec.simulation ? spec.simulation->preset.model.kinetic_energy : KineticEnergy::complete;
  if (const fields::Json* value = object.find("kinetic_energy")) {
    kinetic_energy = parse_kinetic_energy(fields::read_string(*value, "kinetic_energy"), "kinetic_energy");
  }
  const std::string preset_name = object.has("preset")       ? fields::read_string(*object.find("preset"), "preset")
                                  : spec.simulation.has_value() ? spec.simulation->preset.name
                                                                : std::string("cedro2009");
  spec.preset = find_preset(preset_name, kinetic_energy);
  const int joints = spec.preset.model.joint_count();
  if (spec.simulation && spec.simulation->preset.model.joint_count() != joints) {
    throw InputError("preset", "the model (" + spec.preset.name + ") has " + std::to_string(joints) +
                                   " joints but the simulated robot (" + spec.simulation->preset.name + ") has " +
                                   std::to_string(spec.simulation->preset.model.joint_count()));
  }

  // Options: the defaults of `manipid identify` (command_identify.cpp), then the request's.
  IdentificationOptions& options = spec.options;
  options.initial = spec.preset.initial_parameters;
  // The gains that drove the data: the simulation's when it is given (it may override them);
  // for a dataset, estimated from its tau, q and ref (core), the preset's only when it has no tau.
  if (spec.simulation) options.controller = spec.simulation->preset.controller;
  options.assumed_controller = spec.preset.controller;

  if (const fields::Json* method = object.find("method")) {
    options.method = parse_identification_method(fields::read_string(*method, "method"), "method");
  }
  if (const fields::Json* algorithm = object.find("algorithm")) {
    const std::string name = fields::read_string(*algorithm, "algorithm");
    const std::vector<std::string> algorithms = identification_algorithms();
    if (std::find(algorithms.begin(), algorithms.end(), name) == algorithms.end()) {
      throw InputError("algorithm", "unknown algorithm \"" + name + "\" (expected one of " + joined(algorithms) + ")");
    }
    options.algorithm = name;
  }
  // Output-error has no gradient (core's resolve_algorithm owns the rule): say so now.
  resolve_algorithm(options.method, options.algorithm);
  if (const fields::Json* free = object.find("free")) read_free(*free, joints, options.free);
  if (const fields::Json* initial = object.find("initial")) {
    Eigen::VectorXd theta = options.initial.vector();
    fields::read_parameter_object(*initial, "initial", joints, true,
                                  [&](int index, double number, const std::string&) { theta[index] = number; });
    options.initial = Parameters::from_vector(theta);
    check_parameter_ranges(options.initial, "initial");
  }
  read_bounds(object, joints, options);
  const fields::Json* kp = object.find("kp");
  const fields::Json* kd = object.find("kd");
  if ((kp || kd) && !options.controller) options.controller = spec.preset.controller;  // one given: the other the preset's
  if (kp) options.controller->kp = fields::read_gains(*kp, "kp", joints);
  if (kd) options.controller->kd = fields::read_gains(*kd, "kd", joints);

  if (const fields::Json* half_length = object.find("half_length")) {
    if (half_length->is_string() && half_length->get_ref<const std::string&>() == "auto") {
      options.half_length = 0;
    } else if (half_length->is_number()) {
      options.half_length = static_cast<int>(fields::read_integer(*half_length, "half_length", 2, max_half_length));
    } else {
      throw InputError("half_length", "half_length must be \"auto\" or an integer in 2.." + std::to_string(max_half_length) +
                                          ", got " + fields::describe(*half_length));
    }
  }
  if (const fields::Json* band = object.find("band")) {
    if (band->is_string() && band->get_ref<const std::string&>() == "auto") {
      options.band = 0.0;
    } else if (band->is_number()) {
      options.band = fields::read_positive(*band, "band", std::numbers::pi, " rad/sample");
      validate_band(options.band, "band");
    } else {
      throw InputError("band", "band must be \"auto\" or a number in (0, pi] rad/sample, got " + fields::describe(*band));
    }
  }
  if (const fields::Json* source = object.find("torque_source")) {
    const std::string text = fields::read_choice(*source, "torque_source", {"auto", "measured", "reference"});
    options.torque_source = text == "measured"    ? TorqueSource::measured
                            : text == "reference" ? TorqueSource::reference
                                                  : TorqueSource::automatic;
  }
  if (const fields::Json* weights = object.find("weights")) {
    const std::string text = fields::read_choice(*weights, "weights", {"unit", "inverse-variance"});
    options.weighting = text == "inverse-variance" ? JointWeighting::inverse_variance : JointWeighting::unit;
  }
  if (const fields::Json* evaluations = object.find("max_evaluations")) {
    options.max_evaluations = static_cast<int>(fields::read_integer(*evaluations, "max_evaluations", 1, 100'000'000));
  }
  if (const fields::Json* seconds = object.find("max_seconds")) {
    options.max_seconds = fields::read_positive(*seconds, "max_seconds", max_seconds_limit, " s");
  }
  if (const fields::Json* tolerance = object.find("relative_x_tolerance")) {
    options.relative_x_tolerance = fields::read_non_negative(*tolerance, "relative_x_tolerance");
  }
  if (const fields::Json* tolerance = object.find("relative_f_tolerance")) {
    options.relative_f_tolerance = fields::read_non_negative(*tolerance, "relative_f_tolerance");
  }
  if (const fields::Json* iterations = object.find("output_error_iterations")) {
    options.output_error_iterations = static_cast<int>(fields::read_integer(*iterations, "output_error_iterations", 0, 1000));
  }

  if (const fields::Json* truth = object.find("truth")) {
    spec.truth = Eigen::VectorXd::Constant(2 * joints, std::numeric_limits<double>::quiet_NaN());
    fields::read_parameter_object(*truth, "truth", joints, true,
                                  [&](int index, double number, const std::string&) { spec.truth[index] = number; });
  }

  // A simulation's data is known now (it always has tau and ref): check it like a dataset's.
  if (spec.simulation) check_against_data(spec, joints, fields::simulation_samples(*spec.simulation), true, true);
  return spec;
}

Eigen::VectorXd known_truth(const IdentificationSpec& spec, const SimulationSpec* simulation) {
  if (spec.truth.size() > 0) return spec.truth;
  if (spec.simulation) simulation = &*spec.simulation;
  if (simulation && simulation->parameters.joint_count() == spec.preset.model.joint_count()) {
    return simulation->parameters.vector();
  }
  return {};
}

void check_against_data(const IdentificationSpec& spec, int joints, int samples, bool has_torque, bool has_reference) {
  const IdentificationOptions& options = spec.options;
  const int model_joints = spec.preset.model.joint_count();
  const std::string field = data_field(spec);
  const std::string noun = data_noun(spec);
  if (joints != model_joints) {
    throw InputError(field, noun + " has " + std::to_string(joints) + " joints, the model (" + spec.preset.name +
                                ") has " + std::to_string(model_joints));
  }
  if (options.method != IdentificationMethod::input_error && !has_reference) {
    throw InputError("method", std::string(to_string(options.method)) +
                                   " simulates the closed loop from the recorded reference: " + noun +
                                   " has no ref columns, and without the reference r the controller followed "
                                   "(tau = Kp (r - q) - Kd qd) the loop cannot be simulated; input-error needs only q "
                                   "and tau");
  }
  if (options.torque_source == TorqueSource::measured && !has_torque) {
    throw InputError("torque_source", "torque_source \"measured\" needs the tau columns: " + noun + " has none");
  }
  if (options.torque_source == TorqueSource::reference && !has_reference) {
    throw InputError("torque_source", "torque_source \"reference\" needs the ref columns: " + noun + " has none");
  }
  if (!has_torque && !has_reference) {
    throw InputError(field, noun + " has neither tau nor ref columns: the torque can be neither measured nor "
                                   "formed from the reference and the PD gains");
  }

  const auto needed = DifferentialFilter::min_input_samples;
  if (options.method == IdentificationMethod::output_error) {
    if (samples < needed(output_error_structure_half_length)) {
      throw InputError(field, noun + " has " + std::to_string(samples) + " samples; output-error needs at least " +
                                  std::to_string(needed(output_error_structure_half_length)) +
                                  " (its identifiability analysis filters with M = 100)");
    }
  } else if (options.half_length > 0) {
    if (samples < needed(options.half_length)) {
      throw InputError("half_length", "the filter with half_length M = " + std::to_string(options.half_length) +
                                          " needs at least 2M+2 = " + std::to_string(needed(options.half_length)) +
                                          " samples; " + noun + " has " + std::to_string(samples));
    }
  } else if (samples < needed(smallest_automatic_half_length)) {
    throw InputError(field, noun + " has " + std::to_string(samples) + " samples; the input-error filter needs at least " +
                                std::to_string(needed(smallest_automatic_half_length)) +
                                " (with M = 2, the shortest the automatic choice falls back to)");
  }
}

}  // namespace manipid::api

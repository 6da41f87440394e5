// requests_robot.cpp — URDF robot uploads and their identification requests (robot_requests.h).
#include "json_fields.h"
#include "manipid/api/robot_json.h"
#include "manipid/api/robot_requests.h"
#include "manipid/core/robot/urdf.h"
#include "manipid/core/signal/filters.h"

#include <numbers>

namespace manipid::api {
namespace {

/// "weights": "unit" (the default) or "per-joint" — each joint's rows divided by its residual RMS from a first fit.
estimation::JointWeighting read_weights(const fields::ObjectFields& object) {
  const fields::Json* weights = object.find("weights");
  if (!weights) return estimation::JointWeighting::unit;
  return fields::read_choice(*weights, "weights", {"unit", "per-joint"}) == "per-joint" ? estimation::JointWeighting::per_joint
                                                                                        : estimation::JointWeighting::unit;
}

/// A non-empty array of joint numbers (1-based, as users count them) → 0-based indices; whether each is one of
/// the robot's is checked against the robot.
std::vector<int> read_joint_numbers(const fields::Json& value, const std::string& field) {
  if (!value.is_array() || value.empty()) {
    throw InputError(field, field + " must be an array of joint numbers (1-based), got " + fields::describe(value));
  }
  std::vector<int> joints;
  for (std::size_t i = 0; i < value.size(); ++i) {
    joints.push_back(static_cast<int>(fields::read_integer(value[i], fields::element_path(field, i), 1, 1000)) - 1);
  }
  return joints;
}

constexpr std::size_t max_id_length = 64;
/// The largest URDF a robot may have: real arms' files are tens of kilobytes (with meshes referenced,
/// not inlined); 4 MiB leaves room for generated documents without letting one request fill the store.
constexpr std::size_t max_urdf_bytes = 4u << 20;

std::string read_id(const fields::Json& value, const std::string& field) {
  const std::string id = fields::read_string(value, field);
  if (id.empty()) throw InputError(field, field + " is empty");
  if (id.size() > max_id_length) throw InputError(field, field + " is longer than " + std::to_string(max_id_length) + " characters");
  return id;
}

int half_length_field(const fields::Json& value, const std::string& field) {
  if (value.is_string() && value.get_ref<const std::string&>() == "auto") return 0;
  if (value.is_number()) return static_cast<int>(fields::read_integer(value, field, 2, 1'000'000));
  throw InputError(field, field + " must be \"auto\" or an integer in 2..1000000, got " + fields::describe(value));
}

double band_field(const fields::Json& value, const std::string& field) {
  if (value.is_string() && value.get_ref<const std::string&>() == "auto") return 0.0;
  if (value.is_number()) {
    const double band = fields::read_positive(value, field, std::numbers::pi, " rad/sample");
    validate_band(band, field);
    return band;
  }
  throw InputError(field, field + " must be \"auto\" or a number in (0, pi] rad/sample, got " + fields::describe(value));
}

/// `friction` (an array of viscous, coulomb, offset; [] for none) and `armature`, when present,
/// into the parameter layout: identifications and excitation designs take them alike.
void read_layout(const fields::ObjectFields& object, robot::ParameterLayout& layout) {
  if (const fields::Json* friction = object.find("friction")) {
    if (!friction->is_array()) {
      throw InputError("friction", "friction must be an array of viscous, coulomb, offset (or [] for none), got " +
                                       fields::describe(*friction));
    }
    std::vector<std::string> terms;
    for (std::size_t i = 0; i < friction->size(); ++i) {
      terms.push_back(fields::read_string((*friction)[i], fields::element_path("friction", i)));
    }
    if (terms.empty()) terms.emplace_back("none");
    parse_friction(terms, layout, "friction");
  }
  if (const fields::Json* armature = object.find("armature")) {
    if (!armature->is_boolean()) throw InputError("armature", "armature must be true or false, got " + fields::describe(*armature));
    layout.armature = armature->get<bool>();
  }
}

}  // namespace

RobotUpload robot_from_json(const nlohmann::json& body) {
  const fields::ObjectFields object(body, "", {"name", "urdf", "base", "tip"});
  RobotUpload upload;
  const fields::Json* urdf = object.find("urdf");
  if (!urdf) throw InputError("urdf", "missing urdf: the robot's URDF document as a string");
  if (!urdf->is_string()) throw InputError("urdf", "urdf must be the URDF document as a string, got " + fields::describe(*urdf));
  upload.urdf = urdf->get<std::string>();
  if (const fields::Json* name = object.find("name")) upload.name = fields::read_label(*name, "name");
  if (const fields::Json* base = object.find("base")) upload.base = fields::read_string(*base, "base");
  if (const fields::Json* tip = object.find("tip")) upload.tip = fields::read_string(*tip, "tip");
  return upload;
}

ParsedRobot parse_robot(const RobotUpload& upload) {
  if (upload.urdf.empty()) throw InputError("urdf", "the URDF document is empty");
  if (upload.urdf.size() > max_urdf_bytes) {
    throw InputError("urdf", "the URDF document has " + std::to_string(upload.urdf.size()) + " bytes, at most " +
                                 std::to_string(max_urdf_bytes) + " are accepted");
  }
  robot::UrdfOptions options;
  options.base = upload.base;
  options.tip = upload.tip;
  try {
    robot::ParsedUrdf parsed = robot::parse_urdf(upload.urdf, options);
    if (parsed.model.joint_count() > limits::max_robot_joints) {
      throw InputError("urdf", "the URDF chain has " + std::to_string(parsed.model.joint_count()) +
                                   " moving joints; the service takes chains of at most " +
                                   std::to_string(limits::max_robot_joints) +
                                   " (a manipulator has 6 or 7): name a sub-chain with base and tip");
    }
    return {std::move(parsed.model), std::move(parsed.warnings)};
  } catch (const InputError& error) {
    // The core names the element ("joint j3", "link l4"): the request's field is the document, and the
    // element goes into the message.
    if (error.field() == "base" || error.field() == "tip") throw;
    const std::string element = error.field() == "urdf" ? "" : error.field() + ": ";
    const std::string message = error.what();
    throw InputError("urdf", message.rfind(element, 0) == 0 ? message : element + message);
  }
}

bool names_a_robot(const nlohmann::json& body) { return body.is_object() && body.contains("robot_id"); }

namespace {

/// "auto" → `automatic`, else a positive number (in `unit`) up to `largest`.
double number_or_auto(const fields::Json& value, const std::string& field, double automatic, double largest,
                      const char* unit) {
  if (value.is_string() && value.get_ref<const std::string&>() == "auto") return automatic;
  if (value.is_number()) return fields::read_positive(value, field, largest, unit);
  throw InputError(field, field + " must be \"auto\" or a positive number" + unit + ", got " + fields::describe(value));
}

/// One id or an array of ids (at most `most`), from `single` or `plural` (not both).
std::vector<std::string> read_ids(const fields::ObjectFields& object, const std::string& single, const std::string& plural,
                                  std::size_t most) {
  const fields::Json* one = object.find(single);
  const fields::Json* many = object.find(plural);
  if (one && many) throw InputError(plural, "give " + single + " or " + plural + ", not both");
  std::vector<std::string> ids;
  if (one) ids.push_back(read_id(*one, single));
  if (many) {
    if (!many->is_array() || many->empty() || many->size() > most) {
      throw InputError(plural, plural + " must be an array of 1 to " + std::to_string(most) + " dataset ids, got " +
                                   fields::describe(*many));
    }
    for (std::size_t i = 0; i < many->size(); ++i) ids.push_back(read_id((*many)[i], fields::element_path(plural, i)));
  }
  return ids;
}

/// The robot and runs (RobotRuns): robot_id, then the training runs (required) and the validation runs.
RobotRuns read_robot_runs(const fields::ObjectFields& object, const char* missing_robot) {
  RobotRuns runs;
  const fields::Json* robot_id = object.find("robot_id");
  if (!robot_id) throw InputError("robot_id", std::string("missing robot_id: ") + missing_robot);
  runs.robot_id = read_id(*robot_id, "robot_id");
  runs.dataset_ids = read_ids(object, "dataset_id", "dataset_ids", kMostRuns);
  if (runs.dataset_ids.empty()) {
    throw InputError("dataset_id", "missing dataset_id (or dataset_ids): the measured run(s) to identify from");
  }
  runs.dataset_id = runs.dataset_ids.front();
  runs.validation_dataset_ids = read_ids(object, "validation_dataset_id", "validation_dataset_ids", kMostRuns);
  if (!runs.validation_dataset_ids.empty()) runs.validation_dataset_id = runs.validation_dataset_ids.front();
  return runs;
}

/// "trim": [start, end] s and "dt": s, the runs' preparation (resample.h).
void read_preparation(const fields::ObjectFields& object, DataPreparation& preparation) {
  if (const fields::Json* trim = object.find("trim")) {
    if (!trim->is_array() || trim->size() != 2) {
      throw InputError("trim", "trim must be [start, end]: the seconds dropped at each end, got " + fields::describe(*trim));
    }
    preparation.trim_start = fields::read_non_negative((*trim)[0], "trim[0]");
    preparation.trim_end = fields::read_non_negative((*trim)[1], "trim[1]");
  }
  if (const fields::Json* dt = object.find("dt")) {
    preparation.uniform.dt = fields::read_positive(*dt, "dt", kLongestSamplePeriod, " s");
    if (preparation.uniform.dt < kShortestSamplePeriod) {
      throw InputError("dt", "dt must be at least " + fields::format_number(kShortestSamplePeriod) + " s");
    }
  }
}

/// "physical": true or false (default false): an estimate over real rigid bodies only.
bool read_physical(const fields::ObjectFields& object) {
  const fields::Json* physical = object.find("physical");
  if (!physical) return false;
  if (!physical->is_boolean()) throw InputError("physical", "physical must be true or false, got " + fields::describe(*physical));
  return physical->get<bool>();
}

/// The highest cut-off a request may name, Hz (the comparison low-pass's, the judge's).
constexpr double kHighestCutoff = 1e6;

/// "judge_cutoff": Hz and "judge_trim": s, what every torque figure is judged under (signal/judge.h).
void read_judge(const fields::ObjectFields& object, JudgeOptions& judge) {
  if (const fields::Json* value = object.find("judge_cutoff")) {
    judge.cutoff_hz = fields::read_positive(*value, "judge_cutoff", kHighestCutoff, " Hz");
  }
  if (const fields::Json* value = object.find("judge_trim")) judge.trim_seconds = fields::read_non_negative(*value, "judge_trim");
}

/// "torque_joints": 1-based joint numbers, as 0-based indices.
void read_torque_joints(const fields::ObjectFields& object, std::vector<int>& torque_joints) {
  if (const fields::Json* joints = object.find("torque_joints")) torque_joints = read_joint_numbers(*joints, "torque_joints");
}

/// The paper preset's options: a request on a stored robot refuses each by name, saying why, rather than
/// "unknown field".
const std::vector<std::string>& preset_only_fields() {
  static const std::vector<std::string> names = {
      "simulation", "preset", "kinetic_energy", "method", "algorithm", "free", "initial", "lower", "upper", "kp", "kd",
      "torque_source", "max_evaluations", "max_seconds", "relative_x_tolerance", "relative_f_tolerance",
      "output_error_iterations"};
  return names;
}

/// Throws InputError(key, key + `why`) for the first of `keys` the body has.
void refuse_fields(const nlohmann::json& body, const std::vector<std::string>& keys, const std::string& why) {
  if (!body.is_object()) return;
  for (const std::string& key : keys) {
    if (body.contains(key)) throw InputError(key, key + why);
  }
}

}  // namespace

RobotIdentificationSpec robot_identification_from_json(const nlohmann::json& body) {
  refuse_fields(body, preset_only_fields(),
                " belongs to the paper's preset model; a URDF robot (robot_id) is identified by linear input-error: its "
                "options are friction, armature, physical, trim, dt, the filters, ridge, judge_cutoff, judge_trim, "
                "torque_joints and weights");
  if (body.is_object()) {
    for (const char* key : {"comparison_half_length", "comparison_band"}) {
      if (body.contains(key)) {
        throw InputError(key, std::string(key) + " no longer exists: the comparison low-pass is a zero-phase Butterworth "
                                                 "filter, set by comparison_cutoff (Hz, or \"auto\": chosen by held-out "
                                                 "prediction)");
      }
    }
  }
  const fields::ObjectFields object(body, "",
                                    {"robot_id", "dataset_id", "dataset_ids", "validation_dataset_id",
                                     "validation_dataset_ids", "friction", "armature", "physical", "trim", "dt",
                                     "half_length", "band", "comparison_cutoff", "ridge", "judge_cutoff", "judge_trim",
                                     "torque_joints", "weights"});
  RobotIdentificationSpec spec;
  static_cast<RobotRuns&>(spec) = read_robot_runs(object, "the stored robot to identify");
  robot::IdentificationOptions& options = spec.options;
  // Friction: "auto" (the default: chosen by held-out prediction) or the terms.
  const fields::Json* friction = object.find("friction");
  if (!friction || (friction->is_string() && friction->get_ref<const std::string&>() == "auto")) {
    options.friction_auto = true;
    options.layout.viscous = options.layout.coulomb = options.layout.offset = true;
    if (const fields::Json* armature = object.find("armature")) {
      if (!armature->is_boolean()) throw InputError("armature", "armature must be true or false, got " + fields::describe(*armature));
      options.layout.armature = armature->get<bool>();
    }
  } else {
    read_layout(object, options.layout);
  }
  spec.physical = read_physical(object);
  options.physical = spec.physical;
  read_preparation(object, options.preparation);
  if (const fields::Json* value = object.find("half_length")) options.half_length = half_length_field(*value, "half_length");
  if (const fields::Json* value = object.find("band")) options.band = band_field(*value, "band");
  if ((options.half_length > 0) != (options.band > 0.0)) {
    throw InputError(options.band > 0.0 ? "half_length" : "band", "give half_length and band together, or neither");
  }
  if (const fields::Json* value = object.find("comparison_cutoff")) {
    options.comparison_cutoff_hz = number_or_auto(*value, "comparison_cutoff", 0.0, kHighestCutoff, " Hz");
  }
  if (const fields::Json* value = object.find("ridge")) {
    if (value->is_number() && value->get<double>() == 0.0) {
      options.ridge = 0.0;
    } else {
      options.ridge = number_or_auto(*value, "ridge", -1.0, 1.0, "");
    }
  }
  read_judge(object, options.judge);
  read_torque_joints(object, options.torque_joints);
  options.weighting = read_weights(object);
  return spec;
}

namespace {

/// fields::read_positive, its refusal saying what the field is for.
double with_hint(const fields::Json& value, const char* field, double largest, const char* unit, const char* hint) {
  try {
    return fields::read_positive(value, field, largest, unit);
  } catch (const InputError& error) {
    throw InputError(error.field(), std::string(error.what()) + ": " + hint);
  }
}

}  // namespace

bool asks_for_payload(const nlohmann::json& body) { return body.is_object() && body.contains("payload"); }

PayloadIdentificationSpec payload_identification_from_json(const nlohmann::json& body) {
  refuse_fields(body, preset_only_fields(),
                " belongs to the paper's preset model; a payload is identified on a stored robot (robot_id) by linear "
                "least squares: its options are arm_job_id, known_mass, known_centre_of_mass, physical, trim, dt, "
                "comparison_cutoff, judge_cutoff, judge_trim, torque_joints and weights");
  refuse_fields(body, {"friction", "armature", "half_length", "band", "ridge"},
                " belongs to the arm's identification: a payload identification takes the arm as identified from "
                "arm_job_id (a succeeded robot_identification of the same robot, its friction included), or the URDF's "
                "values without it");
  const fields::ObjectFields object(body, "",
                                    {"payload", "robot_id", "arm_job_id", "dataset_id", "dataset_ids",
                                     "validation_dataset_id", "validation_dataset_ids", "known_mass",
                                     "known_centre_of_mass", "physical", "trim", "dt", "comparison_cutoff",
                                     "judge_cutoff", "judge_trim", "torque_joints", "weights"});
  const fields::Json* payload = object.find("payload");
  if (!payload || !payload->is_boolean() || !payload->get<bool>()) {
    throw InputError("payload", "payload must be true (a payload on the robot's tip link), got " +
                                    (payload ? fields::describe(*payload) : std::string("nothing")) +
                                    "; leave it out to identify the robot's arm");
  }
  PayloadIdentificationSpec spec;
  static_cast<RobotRuns&>(spec) = read_robot_runs(object, "the stored robot the payload is mounted on");
  if (const fields::Json* arm = object.find("arm_job_id")) spec.arm_job_id = read_id(*arm, "arm_job_id");
  robot::PayloadOptions& options = spec.options;
  if (const fields::Json* mass = object.find("known_mass")) {
    options.known_mass = with_hint(*mass, "known_mass", 1e6, " kg", "the payload's mass when known; leave it out to estimate it");
  }
  if (const fields::Json* centre = object.find("known_centre_of_mass")) {
    if (!centre->is_array() || centre->size() != 3) {
      throw InputError("known_centre_of_mass", "known_centre_of_mass must be [x, y, z]: the payload's centre of mass in "
                                                   "the tip link's frame, m, got " + fields::describe(*centre));
    }
    Eigen::Vector3d point;
    for (std::size_t i = 0; i < 3; ++i) {
      point[static_cast<Eigen::Index>(i)] = fields::read_number((*centre)[i], fields::element_path("known_centre_of_mass", i));
    }
    options.known_centre_of_mass = point;
  }
  options.physical = read_physical(object);
  read_preparation(object, options.preparation);
  if (const fields::Json* value = object.find("comparison_cutoff")) {
    options.comparison_cutoff_hz = with_hint(*value, "comparison_cutoff", kHighestCutoff, " Hz",
                                             "leave it out to choose it by held-out error, as for the arm");
  }
  read_judge(object, options.judge);
  read_torque_joints(object, options.torque_joints);
  options.weighting = read_weights(object);
  return spec;
}

namespace {

/// A per-joint limit: one positive number for every joint, or an array of them (one per joint; the count
/// is checked against the robot by the core).
Eigen::VectorXd read_joint_limits(const fields::Json& value, const std::string& field, const std::string& unit) {
  if (value.is_number()) return Eigen::VectorXd::Constant(1, fields::read_positive(value, field));
  if (value.is_array() && !value.empty()) {
    Eigen::VectorXd values(static_cast<Eigen::Index>(value.size()));
    for (std::size_t i = 0; i < value.size(); ++i) {
      values[static_cast<Eigen::Index>(i)] = fields::read_positive(value[i], fields::element_path(field, i));
    }
    return values;
  }
  throw InputError(field, field + " must be a number or one number per joint, " + unit + ", got " + fields::describe(value));
}

}  // namespace

ExcitationSpec excitation_from_json(const nlohmann::json& body) {
  const fields::ObjectFields object(body, "",
                                    {"robot_id", "name", "period", "harmonics", "criterion", "target", "moving_joints", "max_acceleration",
                                     "max_velocity", "max_jerk", "max_torque", "torque_parameters", "start_pose",
                                     "position_margin", "duration", "dt", "friction", "armature", "seed", "max_seconds",
                                     "max_evaluations"});
  ExcitationSpec spec;
  const fields::Json* robot_id = object.find("robot_id");
  if (!robot_id) throw InputError("robot_id", "missing robot_id: the robot to design the excitation for");
  spec.robot_id = read_id(*robot_id, "robot_id");
  robot::ExcitationOptions& options = spec.options;
  if (const fields::Json* name = object.find("name")) spec.name = fields::read_label(*name, "name");
  if (const fields::Json* period = object.find("period")) options.period = fields::read_positive(*period, "period", 3600.0, " s");
  if (const fields::Json* harmonics = object.find("harmonics")) {
    options.harmonics = static_cast<int>(fields::read_integer(*harmonics, "harmonics", 2, 20));
  }
  if (const fields::Json* criterion = object.find("criterion")) {
    options.criterion = robot::parse_excitation_criterion(
        fields::read_choice(*criterion, "criterion", {"condition", "logdet"}), "criterion");
  }
  if (const fields::Json* target = object.find("target")) {
    options.target = robot::parse_excitation_target(fields::read_choice(*target, "target", {"arm", "payload"}), "target");
  }
  if (const fields::Json* joints = object.find("moving_joints")) options.moving_joints = read_joint_numbers(*joints, "moving_joints");
  if (const fields::Json* value = object.find("max_acceleration")) {
    options.max_acceleration = read_joint_limits(*value, "max_acceleration", "rad/s^2");
  }
  if (const fields::Json* value = object.find("max_velocity")) options.max_velocity = read_joint_limits(*value, "max_velocity", "rad/s");
  if (const fields::Json* value = object.find("max_jerk")) options.max_jerk = read_joint_limits(*value, "max_jerk", "rad/s^3");
  if (const fields::Json* value = object.find("max_torque")) options.max_torque = read_joint_limits(*value, "max_torque", "N m");
  if (const fields::Json* pose = object.find("start_pose")) {
    if (!pose->is_array() || pose->empty()) {
      throw InputError("start_pose", "start_pose must be an array of joint positions (rad, m prismatic), one per joint, got " +
                                         fields::describe(*pose));
    }
    options.start_pose.resize(static_cast<Eigen::Index>(pose->size()));
    for (std::size_t i = 0; i < pose->size(); ++i) {
      options.start_pose[static_cast<Eigen::Index>(i)] = fields::read_number((*pose)[i], fields::element_path("start_pose", i));
    }
  }
  if (const fields::Json* model = object.find("torque_parameters")) {
    fields::require_object(*model, "torque_parameters");
    spec.torque_parameters = *model;
  }
  if (const fields::Json* margin = object.find("position_margin")) {
    options.position_margin = fields::read_non_negative(*margin, "position_margin");
  }
  if (const fields::Json* dt = object.find("dt")) spec.dt = fields::read_positive(*dt, "dt", 1.0, " s");
  if (const fields::Json* duration = object.find("duration")) {
    spec.periods = robot::whole_periods(fields::read_positive(*duration, "duration", 86'400.0, " s"), options.period);
  }
  read_layout(object, options.layout);
  if (const fields::Json* seed = object.find("seed")) options.seed = fields::read_unsigned(*seed, "seed");
  if (const fields::Json* seconds = object.find("max_seconds")) options.max_seconds = fields::read_positive(*seconds, "max_seconds", 600.0, " s");
  // The budget that makes a design reproducible (max_seconds depends on the machine).
  if (const fields::Json* evaluations = object.find("max_evaluations")) {
    options.max_evaluations = static_cast<int>(fields::read_integer(*evaluations, "max_evaluations", 1, 1'000'000));
  }
  robot::check_sampling(options.period, options.harmonics, spec.dt, spec.periods);
  const double samples = options.period * spec.periods / spec.dt + 1.0;
  if (samples > fields::max_samples) {
    throw InputError("duration", "the excitation would have " + fields::format_number(samples) + " samples, at most " +
                                     fields::format_number(fields::max_samples) + " are allowed");
  }
  return spec;
}

robot::ExcitationOptions excitation_options(const ExcitationSpec& spec, const robot::Model& model) {
  robot::ExcitationOptions options = spec.options;
  if (!spec.torque_parameters.is_null()) {
    const ParameterValues values = parameters_from_json(model, spec.torque_parameters, "torque_parameters");
    options.torque_layout = values.layout;
    options.torque_parameters = values.values;
  }
  return options;
}

void check_excitation(const ExcitationSpec& spec, const robot::Model& model) {
  // The robot's limits leave room; per-joint sizes match; the torque model fits the robot.
  (void)robot::excitation_limits(model, excitation_options(spec, model));
  // The designed dataset holds t, q, qd and qdd: it must fit the store like an upload.
  const double samples = spec.options.period * spec.periods / spec.dt + 1.0;
  limits::check_dataset_size(static_cast<long long>(samples), model.joint_count(), 3, "duration",
                             "the excitation's duration / dt");
}

void check_robot_data(int robot_joints, const std::string& robot_name, int data_joints, bool has_torque,
                      const std::string& field) {
  const std::string noun = field.rfind("validation_dataset_id", 0) == 0 ? "the validation dataset" : "the dataset";
  if (data_joints != robot_joints) {
    throw InputError(field, noun + " has " + std::to_string(data_joints) + " joints, the robot " + robot_name + " has " +
                                std::to_string(robot_joints));
  }
  if (!has_torque) throw InputError(field, noun + " has no tau columns: identifying a robot needs measured torques");
}

}  // namespace manipid::api

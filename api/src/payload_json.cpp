// payload_json.cpp — a payload identification to JSON (payload_json.h).
#include "manipid/api/payload_json.h"
#include "json_numbers.h"

#include "manipid/api/robot_json.h"

namespace manipid::api {
namespace {

using Json = nlohmann::ordered_json;
using json_numbers::number;
using json_numbers::numbers;

constexpr const char* kTensorNames[] = {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"};

Json tensor_entries_json(const robot::TensorEntries& entries) {
  Json object = Json::object();
  for (std::size_t i = 0; i < entries.size(); ++i) object[kTensorNames[i]] = number(entries[i]);
  return object;
}

Json point_json(const Eigen::Vector3d& v) { return numbers(Eigen::VectorXd(v)); }

}  // namespace

nlohmann::ordered_json payload_to_json(const robot::Model& model, const robot::PayloadResult& result,
                                       const robot::PayloadOptions& options, const std::string& arm_source,
                                       const std::optional<robot::PayloadValidation>& validation) {
  Json parameters = Json::array();
  for (std::size_t i = 0; i < 10; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    parameters.push_back({{"name", robot::PayloadResult::names()[i]},
                          {"estimate", number(result.estimate[k])},
                          {"std_error", number(result.std_errors[k])},
                          {"data_share", number(result.data_share[k])}});
  }
  Json candidates = Json::array();
  for (const auto& candidate : result.candidates) {
    candidates.push_back({{"comparison_cutoff_hz", number(candidate.cutoff_hz)}, {"held_out_error", number(candidate.held_out_error)}});
  }
  const Json filters = {{"comparison_cutoff_hz", number(result.comparison_cutoff_hz)},
                        {"chosen_by_held_out", !result.candidates.empty()},
                        {"held_out_error", number(result.held_out_error)},
                        {"candidates", candidates}};
  Json joints = Json::array();
  for (int k : result.torque_joints) joints.push_back(model.joints[static_cast<std::size_t>(k)].name);
  Json json = {
      {"method", options.physical ? "payload from the arm's residual torque (least squares over real rigid bodies)"
                                  : "payload from the arm's residual torque (linear least squares)"},
      {"robot", {{"name", model.name}, {"tip_link", model.tip_link}}},
      {"arm", arm_source},
      {"detected", result.detected},
      {"mass", number(result.mass)},
      {"mass_std_error", number(result.mass_std_error)},
      {"centre_of_mass", point_json(result.centre_of_mass)},
      {"centre_of_mass_std_errors", point_json(result.centre_of_mass_std_errors)},
      {"inertia_about_com", tensor_entries_json(result.inertia)},
      {"inertia_std_errors", tensor_entries_json(result.inertia_std_errors)},
      {"parameters", parameters},
      {"undetermined", result.undetermined},
      {"variance_inflation", number(result.variance_inflation)},
      {"given",
       {{"mass", options.known_mass ? number(*options.known_mass) : Json(nullptr)},
        {"centre_of_mass", options.known_centre_of_mass ? point_json(*options.known_centre_of_mass) : Json(nullptr)}}},
      {"filters", filters},
      {"judge", judge_to_json(options.judge)},
      {"torque_joints", joints},
      {"weights", options.weighting == estimation::JointWeighting::per_joint ? "per-joint" : "unit"},
      {"joint_weights", numbers(result.joint_weights)},
      {"rows", result.rows},
      {"fit", {{"arm_only_error", number(result.arm_only_error)}, {"with_payload_error", number(result.with_payload_error)}}},
      {"consistent", result.consistent},
      {"consistency_findings", result.consistency_findings},
  };
  if (result.physical) {
    json["physical"] = {{"least_squares_consistent", result.physical->least_squares_consistent},
                        {"least_squares_findings", result.physical->least_squares_findings},
                        {"relative_cost_increase", number(result.physical->relative_cost_increase)},
                        {"report", result.physical->report}};
  } else {
    json["physical"] = nullptr;
  }
  if (validation) {
    json["validation"] = {{"arm_only", prediction_to_json(validation->arm_only)},
                          {"with_payload", prediction_to_json(validation->with_payload)}};
  }
  json["warnings"] = result.warnings;
  json["wall_seconds"] = number(result.wall_seconds);
  return json;
}

}  // namespace manipid::api

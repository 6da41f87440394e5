// plots.cpp — series for drawing (plots.h).
#include "manipid/api/plots.h"
#include "json_numbers.h"

#include "manipid/api/records.h"
#include "manipid/api/requests.h"
#include "manipid/api/robot_requests.h"
#include "manipid/api/robot_json.h"
#include "manipid/api/robot_result.h"
#include "manipid/core/robot/prediction.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/paper/input_error.h"
#include "manipid/core/signal/resample.h"

#include <algorithm>
#include <cmath>

namespace manipid::api {
namespace {

using Json = nlohmann::ordered_json;
using json_numbers::number;

template <class Column>
Json pick(const Column& column, const std::vector<long>& indices) {
  Json values = Json::array();
  for (long i : indices) values.push_back(number(column[static_cast<Eigen::Index>(i)]));
  return values;
}

Json columns(const Eigen::MatrixXd& matrix, const std::vector<long>& indices) {
  Json joints = Json::array();
  for (Eigen::Index j = 0; j < matrix.cols(); ++j) joints.push_back(pick(matrix.col(j), indices));
  return joints;
}

double rms(const Eigen::VectorXd& values) {
  return values.size() == 0 ? 0.0 : std::sqrt(values.squaredNorm() / static_cast<double>(values.size()));
}

}  // namespace

std::vector<long> plot_indices(long count, long max_points) {
  std::vector<long> indices;
  if (count <= 0) return indices;
  const long stride = thinning_stride(count, max_points);
  indices.reserve(static_cast<std::size_t>(count / stride + 2));
  for (long i = 0; i < count; i += stride) indices.push_back(i);
  if (indices.back() != count - 1) indices.push_back(count - 1);
  return indices;
}

Trajectory thin(const Trajectory& data, long max_points) {
  if (thinning_stride(data.samples(), max_points) == 1) return data;
  const std::vector<long> rows = plot_indices(data.samples(), max_points);
  const auto pick_rows = [&rows](const Eigen::MatrixXd& matrix) {
    if (matrix.cols() == 0) return Eigen::MatrixXd();  // an absent block stays absent
    Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), matrix.cols());
    for (std::size_t r = 0; r < rows.size(); ++r) out.row(static_cast<Eigen::Index>(r)) = matrix.row(rows[r]);
    return out;
  };
  Trajectory thinned;
  thinned.t = pick_rows(data.t);
  thinned.q = pick_rows(data.q);
  thinned.tau = pick_rows(data.tau);
  thinned.ref = pick_rows(data.ref);
  thinned.qd = pick_rows(data.qd);
  thinned.qdd = pick_rows(data.qdd);
  return thinned;
}

nlohmann::ordered_json trajectory_to_json(const Trajectory& data) {
  const std::vector<long> all = plot_indices(data.samples(), 0);
  Json json = {{"t", pick(data.t, all)}, {"q", columns(data.q, all)}};
  if (data.has_torque()) json["tau"] = columns(data.tau, all);
  if (data.has_reference()) json["ref"] = columns(data.ref, all);
  if (data.has_rates()) json["qd"] = columns(data.qd, all);
  if (data.has_accelerations()) json["qdd"] = columns(data.qdd, all);
  return json;
}

nlohmann::ordered_json torque_fit_to_json(const std::string& request_json, const std::string& result_json,
                                          const Trajectory& stored, long max_points) {
  const IdentificationSpec spec = identification_from_json(nlohmann::json::parse(request_json));
  // The samples the identification saw: trimmed and on its uniform grid.
  std::optional<Trajectory> prepared;
  const Trajectory& data = prepare_data(stored, spec.options.preparation, prepared);
  const nlohmann::json result = nlohmann::json::parse(result_json);
  const RobotModel& model = spec.preset.model;
  if (data.joint_count() != model.joint_count()) {
    throw InputError("dataset_id", "the dataset has " + std::to_string(data.joint_count()) + " joints, the model " +
                                       std::to_string(model.joint_count()));
  }

  // The estimate, every parameter (the fixed ones hold their given values).
  const std::vector<std::string> names = parameter_names(model.joint_count());
  // "point", not "estimates": the model needs every parameter, including those the data
  // determine only in combination (their estimates are null).
  if (!result.contains("point") || !result["point"].is_object()) {
    throw InputError("result", "the job's result has no point");
  }
  Eigen::VectorXd theta(static_cast<Eigen::Index>(names.size()));
  Json parameters = Json::object();
  for (std::size_t i = 0; i < names.size(); ++i) {
    theta[static_cast<Eigen::Index>(i)] = stored_result_number(result["point"], names[i].c_str(), "point.");
    parameters[names[i]] = theta[static_cast<Eigen::Index>(i)];
  }

  // The filter and torque the identification used, as its result reports them.
  if (!result.contains("filter") || !result["filter"].is_object()) throw InputError("result", "the job's result has no filter");
  FilterSettings filter;
  filter.half_length = static_cast<int>(stored_result_number(result["filter"], "half_length", "filter."));
  filter.band = stored_result_number(result["filter"], "band", "filter.");
  filter.dt = data.dt();  // the filter's Δ is the data's sample period, whatever the method
  bool from_reference = result.value("torque_source", std::string()) == "reference";
  if (result.value("method", std::string()) == "output-error") {
    // Output-error filters nothing; its result carries the default filter. Show the fit through
    // that filter, with the torque the data has.
    from_reference = !data.has_torque();
  }

  // The gains it used (given, estimated from the data, or assumed), as its result reports them;
  // results stored before they did fall back to the request's gains, then the preset's.
  std::optional<PdController> gains = spec.options.controller ? spec.options.controller : spec.options.assumed_controller;
  if (result.contains("gains") && result["gains"].is_object() && result["gains"].value("kp", Json()).is_array() &&
      result["gains"].value("kd", Json()).is_array()) {
    const Json& kp = result["gains"]["kp"];
    const Json& kd = result["gains"]["kd"];
    const auto joints = static_cast<Eigen::Index>(kp.size());
    if (joints == data.joint_count() && kd.size() == kp.size()) {
      gains = PdController{Eigen::VectorXd(joints), Eigen::VectorXd(joints)};
      for (Eigen::Index j = 0; j < joints; ++j) {
        gains->kp[j] = kp[static_cast<std::size_t>(j)].is_number() ? kp[static_cast<std::size_t>(j)].get<double>() : 0.0;
        gains->kd[j] = kd[static_cast<std::size_t>(j)].is_number() ? kd[static_cast<std::size_t>(j)].get<double>() : 0.0;
      }
    }
  }
  const FilteredData filtered = filter_for_input_error(data, filter, from_reference, gains);
  const TorqueFit fit = torque_fit(model, Parameters::from_vector(theta), data, filtered);
  const Eigen::MatrixXd residual = fit.residual();

  const std::vector<long> indices = plot_indices(fit.t.size(), max_points);
  Json joints = Json::array();
  for (Eigen::Index j = 0; j < fit.model.cols(); ++j) {
    joints.push_back({{"joint", j + 1},
                      {"measured", pick(fit.measured.col(j), indices)},
                      {"model", pick(fit.model.col(j), indices)},
                      {"residual", pick(residual.col(j), indices)},
                      {"rms_measured", number(rms(fit.measured.col(j)))},
                      {"rms_residual", number(rms(residual.col(j)))}});
  }
  return {{"parameters", parameters},
          {"filter", {{"half_length", filter.half_length}, {"band", filter.band}, {"dt", filter.dt}}},
          {"torque_source", from_reference ? "reference" : "measured"},
          {"samples", fit.t.size()},
          {"t", pick(fit.t, indices)},
          {"joints", joints}};
}

namespace {

/// What friction must explain, per judged joint: the measured torque less the rigid-body part of the
/// prediction (π with fv, fc and fo set to 0; the armature Ia·q̈ stays: it is inertia, not friction), both
/// through the judge's low-pass, beside the judge's q̇ at the same instants, and the friction law the point
/// holds. Null when the result estimated none of fv, fc, fo.
Json friction_to_json(const robot::Model& model, const RobotResult& result, const Trajectory& data,
                      const std::vector<long>& indices) {
  const int n = model.joint_count();
  const robot::ParameterLayout& layout = result.layout;
  if (!layout.viscous && !layout.coulomb && !layout.offset) return nullptr;
  Eigen::VectorXd rigid = result.point;
  for (const int begin : {layout.viscous_begin(n), layout.coulomb_begin(n), layout.offset_begin(n)}) {
    if (begin >= 0) rigid.segment(begin, n).setZero();
  }
  const robot::TorquePrediction without = robot::predict_torque(model, layout, rigid, data, result.judge, result.torque_joints);
  const JudgedStates states = judge_states(data, result.judge);
  const JudgedSpan span = judged_span(data.t, result.judge);
  if (span.size() != without.t.size()) throw InputError("result", "the judged span does not match the prediction");
  Json terms = Json::array();
  if (layout.viscous) terms.push_back("viscous");
  if (layout.coulomb) terms.push_back("coulomb");
  if (layout.offset) terms.push_back("offset");
  Json joints = Json::array();
  for (Eigen::Index j = 0; j < without.model.cols(); ++j) {
    const int k = without.joints[static_cast<std::size_t>(j)];
    const Eigen::VectorXd qd = states.qd.col(k).segment(span.first, span.size());
    const Eigen::VectorXd torque = without.measured.col(j) - without.model.col(j);
    Json law = Json::object();
    if (layout.viscous) law["fv"] = number(result.point[layout.viscous_begin(n) + k]);
    if (layout.coulomb) law["fc"] = number(result.point[layout.coulomb_begin(n) + k]);
    if (layout.offset) law["fo"] = number(result.point[layout.offset_begin(n) + k]);
    joints.push_back({{"joint", k + 1},
                      {"name", model.joints[static_cast<std::size_t>(k)].name},
                      {"law", law},
                      {"qd", pick(qd, indices)},
                      {"torque", pick(torque, indices)}});
  }
  return {{"terms", terms}, {"joints", joints}};
}

}  // namespace

namespace {

/// A judged prediction as the robot views draw it: {"judge", "samples", "t", "joints": [{"joint", "name",
/// "measured", "model", "residual", "rms_measured", "rms_residual", "relative_error"}], "overall_relative_error"},
/// the series at `indices`.
Json judged_fit_json(const robot::Model& model, const robot::TorquePrediction& fit, const std::vector<long>& indices) {
  Json joints = Json::array();
  for (Eigen::Index j = 0; j < fit.model.cols(); ++j) {
    const int k = fit.joints[static_cast<std::size_t>(j)];
    const Eigen::VectorXd residual = fit.model.col(j) - fit.measured.col(j);
    joints.push_back({{"joint", k + 1},
                      {"name", model.joints[static_cast<std::size_t>(k)].name},
                      {"measured", pick(fit.measured.col(j), indices)},
                      {"model", pick(fit.model.col(j), indices)},
                      {"residual", pick(residual, indices)},
                      {"rms_measured", number(rms(fit.measured.col(j)))},
                      {"rms_residual", number(rms(residual))},
                      {"relative_error", number(fit.relative_error[j])}});
  }
  return {{"judge", judge_to_json(fit.judge)},
          {"samples", fit.t.size()},
          {"t", pick(fit.t, indices)},
          {"joints", joints},
          {"overall_relative_error", number(fit.overall_relative_error)}};
}

}  // namespace

nlohmann::ordered_json robot_fit_to_json(const robot::Model& model, const std::string& request_json,
                                         const std::string& result_json, const Trajectory& stored, long max_points,
                                         bool prior) {
  const RobotIdentificationSpec spec = robot_identification_from_json(nlohmann::json::parse(request_json));
  const RobotResult result = decode_robot_result(model, nlohmann::json::parse(result_json));
  // The samples the identification saw: trimmed, and on its grid.
  DataPreparation preparation = spec.options.preparation;
  preparation.uniform.dt = result.dt;
  std::optional<Trajectory> prepared;
  const Trajectory& data = prepare_data(stored, preparation, prepared);
  const robot::TorquePrediction fit = robot::predict_torque(model, result.layout, result.point, data, result.judge, result.torque_joints);
  const std::vector<long> indices = plot_indices(fit.t.size(), max_points);
  Json json = judged_fit_json(model, fit, indices);
  if (Json friction = friction_to_json(model, result, data, indices); !friction.is_null()) json["friction"] = std::move(friction);
  if (prior) {
    const robot::TorquePrediction by_urdf =
        robot::predict_torque(model, result.layout, result.prior, data, result.judge, result.torque_joints);
    Json errors = Json::array();
    for (Eigen::Index j = 0; j < by_urdf.relative_error.size(); ++j) errors.push_back(number(by_urdf.relative_error[j]));
    json["prior"] = {{"relative_error", errors}, {"overall_relative_error", number(by_urdf.overall_relative_error)}};
  }
  return json;
}

nlohmann::ordered_json payload_fit_to_json(const robot::Model& model, const std::string& request_json,
                                           const std::string& result_json, const Trajectory& data, long max_points) {
  const PayloadIdentificationSpec spec = payload_identification_from_json(nlohmann::json::parse(request_json));
  const StoredPayload stored = decode_payload_result(model, nlohmann::json::parse(result_json));
  robot::PayloadResult payload;
  payload.estimate = stored.estimate;
  payload.torque_joints = stored.torque_joints;
  // Prepared and judged as the identification's own figures (validate_payload: the request's trim, grid and judge).
  const robot::PayloadValidation prediction = robot::validate_payload(model, stored.arm, payload, {data}, spec.options);
  const robot::TorquePrediction& with = prediction.with_payload;
  const robot::TorquePrediction& without = prediction.arm_only;
  const std::vector<long> indices = plot_indices(with.t.size(), max_points);
  Json json = judged_fit_json(model, with, indices);
  for (Eigen::Index j = 0; j < without.model.cols(); ++j) {
    Json& joint = json["joints"][static_cast<std::size_t>(j)];
    joint["arm_only"] = pick(without.model.col(j), indices);
    joint["arm_only_relative_error"] = number(without.relative_error[j]);
  }
  json["arm_only"] = prediction_to_json(without);
  return json;
}

}  // namespace manipid::api

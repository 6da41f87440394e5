// robot_json.cpp — rigid-body identification results to JSON and parameter vectors back (robot_json.h).
#include "manipid/api/robot_json.h"
#include "json_numbers.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/base_parameters.h"
#include "manipid/core/robot/excitation.h"
#include "manipid/core/robot/link_table.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/api/plots.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <sstream>

namespace manipid::api {
namespace {

using Json = nlohmann::ordered_json;
using json_numbers::by_name;
using json_numbers::number;
using json_numbers::numbers;

Json filter_json(const FilterSettings& filter) {
  return {{"half_length", filter.half_length},
          {"band", filter.band},
          {"dt", filter.dt},
          {"cutoff_hz", number(filter.band / (2.0 * std::numbers::pi * filter.dt))}};
}

Json vector_json(const Eigen::VectorXd& v) {
  Json array = Json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) array.push_back(v[i]);  // ±∞ becomes null
  return array;
}

Json rows_json(const Eigen::MatrixXd& m) {
  Json array = Json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) array.push_back(vector_json(m.row(r).transpose()));
  return array;
}

/// The joints a design moved, by name (all of them when moving_joints is empty).
nlohmann::ordered_json moving_joints_json(const robot::Model& model, const robot::ExcitationOptions& options) {
  nlohmann::ordered_json names = nlohmann::ordered_json::array();
  if (options.moving_joints.empty()) {
    for (const robot::Joint& joint : model.joints) names.push_back(joint.name);
  } else {
    for (int k : options.moving_joints) names.push_back(model.joints[static_cast<std::size_t>(k)].name);
  }
  return names;
}

}  // namespace

nlohmann::ordered_json prediction_to_json(const robot::TorquePrediction& prediction) {
  return {{"relative_error", numbers(prediction.relative_error)},
          {"rms_error", numbers(prediction.rms_error)},
          {"overall_relative_error", number(prediction.overall_relative_error)}};
}

nlohmann::ordered_json judge_to_json(const JudgeOptions& judge) {
  return {{"lowpass", "zero-phase Butterworth, order 4"},
          {"cutoff_hz", number(judge.cutoff_hz)},
          {"trim_seconds", number(judge.trim_seconds)}};
}

nlohmann::ordered_json robot_description(const robot::Model& model, const std::vector<std::string>& warnings) {
  Json joints = Json::array();
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    const robot::Joint& joint = model.joints[k];
    joints.push_back({{"name", joint.name},
                      {"link", joint.link},
                      {"type", robot::to_string(joint.type)},
                      {"axis", {joint.axis.x(), joint.axis.y(), joint.axis.z()}},
                      {"limits",
                       {{"lower", number(joint.limits.lower)},
                        {"upper", number(joint.limits.upper)},
                        {"velocity", number(joint.limits.velocity)},
                        {"effort", number(joint.limits.effort)}}},
                      {"damping", joint.damping},
                      {"friction", joint.friction},
                      // The URDF links whose inertia this body holds (fixed joints merged); not the
                      // top-level "links", which in a resource are its addresses.
                      {"body_links", model.bodies[k].links}});
  }
  const robot::ParameterLayout layout;  // viscous and Coulomb: what a URDF's <dynamics> holds
  const std::vector<std::string> names = robot::standard_parameter_names(model, layout);
  return {{"robot_name", model.name},
          {"base_link", model.base_link},
          {"tip_link", model.tip_link},
          {"joints", joints},
          {"gravity", {model.gravity.x(), model.gravity.y(), model.gravity.z()}},
          {"parameters", {{"names", names}, {"urdf_values", by_name(names, robot::standard_parameters(model, layout))}}},
          {"options", {{"friction", {"viscous", "coulomb", "offset"}}, {"armature", true}}},
          {"base_parameters",
           {{"count", robot::base_parameters(model, layout).size()}, {"friction", friction_names(layout)}}},
          {"warnings", warnings}};
}

std::vector<std::string> friction_names(const robot::ParameterLayout& layout) {
  std::vector<std::string> names;
  if (layout.viscous) names.emplace_back("viscous");
  if (layout.coulomb) names.emplace_back("coulomb");
  if (layout.offset) names.emplace_back("offset");
  return names;
}

void parse_friction(const std::vector<std::string>& terms, robot::ParameterLayout& layout, const std::string& field) {
  layout.viscous = layout.coulomb = layout.offset = false;
  std::set<std::string> seen;
  for (const std::string& term : terms) {
    if (!seen.insert(term).second) throw InputError(field, field + " lists '" + term + "' twice");
    if (term == "viscous") layout.viscous = true;
    else if (term == "coulomb") layout.coulomb = true;
    else if (term == "offset") layout.offset = true;
    else if (term == "none" && terms.size() == 1) continue;
    else {
      throw InputError(field, field + ": unknown friction term '" + term +
                                  "' (expected any of viscous, coulomb, offset, or none alone)");
    }
  }
}

nlohmann::ordered_json robot_result_to_json(const robot::Model& model, const robot::IdentificationResult& result,
                                            const std::optional<robot::ValidationReport>& validation) {
  const robot::TorquePrediction& fit = result.fit;
  const int n = model.joint_count();
  const robot::ParameterLayout& layout = result.layout;
  Json joints = Json::array();
  for (const robot::Joint& joint : model.joints) {
    joints.push_back({{"name", joint.name}, {"link", joint.link}, {"type", robot::to_string(joint.type)}});
  }
  Json base = Json::array();
  for (int i = 0; i < result.base.size(); ++i) {
    const double estimate = result.estimate[i], error = result.std_errors[i];
    // The combination in full precision, for scripts (the name rounds coefficients to 6 digits).
    Json combination = Json::object();
    for (Eigen::Index j = 0; j < result.base.combination.cols(); ++j) {
      const double coefficient = result.base.combination(i, j);
      if (coefficient != 0.0) combination[result.standard_names[static_cast<std::size_t>(j)]] = coefficient;
    }
    base.push_back({{"name", result.base.names[static_cast<std::size_t>(i)]},
                    {"combination", combination},
                    {"estimate", number(estimate)},
                    {"std_error", number(error)},
                    {"relative_std_error", number(estimate != 0.0 ? std::abs(error / estimate) : NAN)},
                    {"data_share", number(result.data_share[i])}});
  }
  Json correlation = Json::array();
  for (Eigen::Index a = 0; a < result.correlation.rows(); ++a) correlation.push_back(numbers(result.correlation.row(a).transpose()));
  Json friction = Json::array();
  for (int k = 0; k < n; ++k) {
    Json entry = {{"joint", model.joints[static_cast<std::size_t>(k)].name}};
    if (layout.viscous) entry["fv"] = number(result.point[layout.viscous_begin(n) + k]);
    if (layout.coulomb) entry["fc"] = number(result.point[layout.coulomb_begin(n) + k]);
    if (layout.offset) entry["fo"] = number(result.point[layout.offset_begin(n) + k]);
    if (layout.armature) entry["Ia"] = number(result.point[layout.armature_begin(n) + k]);
    friction.push_back(entry);
  }
  Json torque_joints = Json::array();
  for (int k : result.torque_joints) torque_joints.push_back(model.joints[static_cast<std::size_t>(k)].name);
  Json candidates = Json::array();
  for (const robot::CandidateScore& candidate : result.candidates) {
    candidates.push_back({{"comparison_cutoff_hz", number(candidate.cutoff_hz)},
                          {"friction", candidate.friction},
                          {"ridge", number(candidate.ridge)},
                          {"held_out_error", number(candidate.held_out_error)}});
  }
  const robot::FilterPair& filters = result.filters;
  Json json = {
      {"method", "input-error (linear least squares)"},
      {"robot", {{"name", model.name}, {"base_link", model.base_link}, {"tip_link", model.tip_link}, {"joints", joints}}},
      {"parameters", {{"friction", friction_names(layout)}, {"armature", layout.armature}}},
      {"base_parameters", base},
      {"correlation", correlation},
      {"condition_number", number(result.condition_number)},
      {"unexcited", result.unexcited},
      {"point", by_name(result.standard_names, result.point)},
      {"prior", by_name(result.standard_names, result.prior)},
      {"unidentifiable", result.unidentifiable},
      {"friction", friction},
      {"filters",
       {{"differentiation", filter_json(filters.differentiation)},
        {"comparison", {{"lowpass", "zero-phase Butterworth, order 4"}, {"cutoff_hz", number(filters.comparison_cutoff_hz)}}},
        {"working_step", filters.working_step},
        {"trim_seconds", number(filters.trim_seconds)}}},
      {"selection",
       {{"by_held_out", result.chosen_by_held_out},
        {"ridge", number(result.ridge)},
        {"held_out_error", number(result.held_out_error)},
        {"candidates", candidates}}},
      {"judge", judge_to_json(result.judge)},
      {"torque_joints", torque_joints},
      {"runs", result.runs},
      {"rows", result.rows},
      {"fit",
       {{"residual_rms", numbers(result.residual_rms)},
        {"relative_error", numbers(fit.relative_error)},
        {"rms_error", numbers(fit.rms_error)},
        {"overall_relative_error", number(fit.overall_relative_error)}}},
  };
  Json links_json = Json::array();
  for (const robot::LinkConsistency& link : result.consistency.links) {
    Json findings = Json::array();
    for (const std::string& finding : result.consistency.findings) {
      if (finding.rfind(link.name + ":", 0) == 0) findings.push_back(finding);
    }
    links_json.push_back({{"link", link.name},
                          {"consistent", link.consistent()},
                          {"mass", number(link.mass)},
                          {"centre_of_mass", numbers(link.centre_of_mass)},
                          {"principal_moments", numbers(link.principal_moments)},
                          {"findings", findings}});
  }
  // The links as a URDF holds them, and what the data determine of each (robot/link_table.h).
  Json table = Json::array();
  for (const robot::LinkRow& row : robot::link_table(model, result)) {
    const Eigen::Matrix3d& I = row.inertia_about_com;
    table.push_back({{"link", row.link},
                     {"mass", number(row.mass)},
                     {"centre_of_mass", numbers(row.centre_of_mass)},
                     {"inertia_about_com",
                      {{"ixx", number(I(0, 0))}, {"ixy", number(I(0, 1))}, {"ixz", number(I(0, 2))},
                       {"iyy", number(I(1, 1))}, {"iyz", number(I(1, 2))}, {"izz", number(I(2, 2))}}},
                     {"consistent", row.consistent},
                     {"determined",
                      {{"mass", row.mass_determined()},
                       {"centre_of_mass", row.centre_of_mass_determined()},
                       {"inertia_about_com", row.inertia_determined()}}}});
  }
  json["links"] = table;
  json["consistency"] = {{"consistent", result.consistency.consistent()},
                         {"links", links_json},
                         {"findings", result.consistency.findings}};
  if (result.physical) {
    const robot::ConsistentFitSummary& fit_summary = *result.physical;
    json["physical"] = {{"converged", fit_summary.converged()},
                        {"termination", robot::to_string(fit_summary.termination)},
                        {"message", fit_summary.message},
                        {"iterations", fit_summary.iterations},
                        {"unconstrained_cost", number(fit_summary.unconstrained_cost)},
                        {"projection_cost", number(fit_summary.projection_cost)},
                        {"final_cost", number(fit_summary.final_cost)},
                        {"cost_increase", number(fit_summary.relative_cost_increase)},
                        {"prior_to_data_ratio", number(fit_summary.regularization_ratio)},
                        {"report", fit_summary.brief_report()}};
  }
  if (validation) {
    Json figures = prediction_to_json(validation->estimate);
    figures["prior"] = prediction_to_json(validation->prior);
    json["validation"] = figures;
  }
  std::vector<std::string> warnings = result.warnings;
  if (validation) {
    for (const std::string& warning : validation->warnings) warnings.push_back("validation data: " + warning);
  }
  json["warnings"] = warnings;
  json["wall_seconds"] = result.wall_seconds;
  return json;
}

std::string identified_urdf_note(const nlohmann::json& result, const std::string& sources) {
  const auto count = [](const nlohmann::json& array) { return array.is_array() ? array.size() : std::size_t{0}; };
  const auto percent_of = [](const nlohmann::json& value) {
    if (!value.is_number()) return std::string("-");
    std::ostringstream text;
    text.precision(3);
    text << 100.0 * value.get<double>() << " %";
    return text.str();
  };
  std::ostringstream note;
  const int runs = result.value("runs", 1);
  note << "Identified by manipid (" << result.value("method", std::string("input-error")) << ", "
       << (result.contains("physical") ? "constrained to physically consistent links" : "unconstrained") << ") from "
       << runs << (runs == 1 ? " run" : " runs") << (sources.empty() ? "" : " (" + sources + ")") << ".\n";
  const nlohmann::json& base = result.contains("base_parameters") ? result.at("base_parameters") : nlohmann::json::array();
  std::size_t seen = 0, mostly_data = 0;
  for (const auto& parameter : base) {
    seen += parameter.contains("std_error") && parameter.at("std_error").is_number() ? 1 : 0;
    mostly_data += parameter.value("data_share", 0.0) >= 0.5 ? 1 : 0;
  }
  note << "The data see " << seen << " of " << count(base) << " base parameters (combinations of the standard ones, "
       << "listed in the result's base_parameters), " << mostly_data << " of them mostly the data's rather than this "
       << "URDF's (data_share); what they do not see keeps this URDF's values.\n";
  if (result.contains("links")) {
    std::vector<std::string> whole, mass_only, combined;
    for (const auto& link : result.at("links")) {
      const nlohmann::json& determined = link.at("determined");
      const std::string name = link.value("link", std::string());
      if (determined.value("inertia_about_com", false)) whole.push_back(name);
      else if (determined.value("mass", false)) mass_only.push_back(name);
      else combined.push_back(name);
    }
    const auto join = [](const std::vector<std::string>& names) {
      std::string text;
      for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
      return text.empty() ? std::string("none") : text;
    };
    note << "Links whose mass, centre of mass and inertia the data determine alone: " << join(whole)
         << "; whose mass alone: " << join(mass_only) << "; seen only in combinations with other links: " << join(combined)
         << ".\n";
  }
  const nlohmann::json judge = result.value("judge", nlohmann::json::object());
  note << "Torque error under the judge (zero-phase 4th-order Butterworth low-pass at "
       << (judge.contains("cutoff_hz") ? judge.at("cutoff_hz").dump() : std::string("?")) << " Hz): training "
       << percent_of(result.value("fit", nlohmann::json::object()).value("overall_relative_error", nlohmann::json()));
  if (result.contains("validation")) {
    note << ", held-out " << percent_of(result.at("validation").value("overall_relative_error", nlohmann::json()))
         << " (the URDF's own values: "
         << percent_of(result.at("validation").value("prior", nlohmann::json::object()).value("overall_relative_error", nlohmann::json()))
         << ")";
  }
  note << ".\nFriction: viscous and Coulomb in each joint's <dynamics damping friction>; offsets and rotor inertias, "
          "which a URDF has no element for, in comments on the joints.";
  return note.str();
}

ParameterValues parameters_from_json(const robot::Model& model, const nlohmann::json& json, const std::string& field) {
  const int n = model.joint_count();
  const nlohmann::json* values = &json;
  if (json.is_object() && json.contains("point")) values = &json.at("point");
  if (!values->is_object()) {
    throw InputError(field, field + " must be an identify result (with \"point\") or an object of parameter values by name");
  }
  // A result's point is exactly what was identified: its names say the layout (friction "none" has no
  // fv). A flat object overrides the URDF's values: everything it does not name, the URDF's damping and
  // friction included, stays as the URDF has it ({"fv2": 0.4} does not drop the Coulomb friction).
  const bool result_point = values != &json;
  ParameterValues result;
  if (result_point) result.layout.viscous = result.layout.coulomb = false;
  const auto has_prefix = [&](const char* prefix) {
    return std::any_of(values->items().begin(), values->items().end(), [&](const auto& item) {
      return item.key().rfind(prefix, 0) == 0 && item.key().size() > std::string(prefix).size() &&
             std::isdigit(static_cast<unsigned char>(item.key()[std::string(prefix).size()]));
    });
  };
  result.layout.viscous = result.layout.viscous || has_prefix("fv");
  result.layout.coulomb = result.layout.coulomb || has_prefix("fc");
  result.layout.offset = has_prefix("fo");
  result.layout.armature = has_prefix("Ia");
  const std::vector<std::string> names = robot::standard_parameter_names(n, result.layout);
  result.values = robot::standard_parameters(model, result.layout);
  for (const auto& item : values->items()) {
    const auto found = std::find(names.begin(), names.end(), item.key());
    if (found == names.end()) {
      throw InputError(field, field + ": '" + item.key() + "' is not a parameter of this " + std::to_string(n) +
                                  "-joint robot (m1, mx1, ..., Izz" + std::to_string(n) + ", fv1, fc1, fo1, Ia1, ...)");
    }
    if (!item.value().is_number() || !std::isfinite(item.value().get<double>())) {
      throw InputError(field, field + ": " + item.key() + " must be a finite number");
    }
    result.values[found - names.begin()] = item.value().get<double>();
  }
  return result;
}

nlohmann::ordered_json excitation_to_json(const robot::Model& model, const robot::ExcitationOptions& design_options,
                                         const robot::ExcitationLimits& limits, const robot::ExcitationDesign& design) {
  const robot::FourierTrajectory& trajectory = design.trajectory;
  const robot::ExcitationSummary& summary = design.summary;
  nlohmann::ordered_json joints = nlohmann::ordered_json::array();
  for (const robot::Joint& joint : model.joints) joints.push_back(joint.name);
  nlohmann::ordered_json active = nlohmann::ordered_json::array();
  for (const robot::ActiveLimit& limit : summary.active_limits) {
    active.push_back({{"joint", limit.joint_name},
                      {"index", limit.joint},
                      {"kind", robot::to_string(limit.kind)},
                      {"peak", limit.peak},
                      {"limit", limit.limit}});
  }
  const robot::ParameterLayout& layout = design_options.layout;
  // Per joint, what the design reaches and the share of each limit it uses: one column per LimitKind,
  // named by it.
  const auto column = [](const Eigen::MatrixXd& m, Eigen::Index c) {
    return c < m.cols() ? vector_json(m.col(c)) : Json::array();
  };
  const auto by_kind = [&column](const Eigen::MatrixXd& m) {
    nlohmann::ordered_json kinds = nlohmann::ordered_json::object();
    for (int kind = 0; kind < robot::kLimitKinds; ++kind) {
      kinds[robot::to_string(static_cast<robot::LimitKind>(kind))] = column(m, kind);
    }
    return kinds;
  };
  nlohmann::ordered_json ramp = nullptr;
  if (design.ramp) {
    ramp = {{"pose", vector_json(design.ramp->pose)},
            {"target", vector_json(design.ramp->target)},
            {"duration", design.ramp->duration},
            {"peaks",
             {{"velocity", column(design.ramp->peaks, 0)},
              {"acceleration", column(design.ramp->peaks, 1)},
              {"jerk", column(design.ramp->peaks, 2)},
              {"torque", column(design.ramp->peaks, 3)}}}};
  }
  nlohmann::ordered_json json{
      {"robot", model.name},
      {"joints", joints},
      {"series", "q_k(t) = q0_k + sum_{l=1..L} [a_kl/(w l) sin(w l t) - b_kl/(w l) cos(w l t)], w = 2 pi / period; "
                 "qd_k(t) = sum_l [a_kl cos(w l t) + b_kl sin(w l t)]"},
      {"period", trajectory.period},
      {"harmonics", trajectory.harmonics()},
      {"angular_frequency", trajectory.angular_frequency()},
      {"q0", vector_json(trajectory.q0)},
      {"a", rows_json(trajectory.a)},
      {"b", rows_json(trajectory.b)},
      {"start", vector_json(trajectory.start())},
      {"criterion", robot::to_string(summary.criterion)},
      {"target", robot::to_string(design_options.target)},
      {"moving_joints", moving_joints_json(model, design_options)},
      {"criterion_value", summary.final_value},
      {"initial_criterion_value", summary.initial_value},
      {"condition_number", summary.condition_number},
      {"log_det", summary.log_det},
      {"base_parameters", summary.base_parameters},
      {"samples", summary.samples},
      {"layout",
       {{"viscous", layout.viscous}, {"coulomb", layout.coulomb}, {"offset", layout.offset}, {"armature", layout.armature}}},
      {"limits",
       {{"lower", vector_json(limits.lower)},
        {"upper", vector_json(limits.upper)},
        {"velocity", vector_json(limits.velocity)},
        {"acceleration", vector_json(limits.acceleration)},
        {"jerk", vector_json(limits.jerk)},
        {"torque", vector_json(limits.torque)},
        {"torque_model", design_options.torque_parameters.size() ? "given parameters" : "the URDF's"},
        {"position_margin", design_options.position_margin}}},
      {"peaks", by_kind(summary.peaks)},
      {"usage", by_kind(summary.usage)},
      {"torque_scale", summary.torque_scale},
      {"active_limits", active},
      {"ramp", ramp},
      {"seed", design_options.seed},
      {"evaluations", summary.evaluations},
      {"max_evaluations", design_options.max_evaluations},
      {"wall_seconds", summary.wall_seconds},
      {"termination", robot::to_string(summary.termination)},
      {"message", summary.message},
  };
  return json;
}

nlohmann::ordered_json excitation_torque_json(const robot::Model& model, const robot::ExcitationLimits& limits,
                                              const robot::SampledExcitation& sampled, long max_points) {
  const std::vector<long> indices = plot_indices(static_cast<long>(sampled.t.size()), max_points);
  const Eigen::Index n = model.joint_count();
  robot::Data data(model);
  Eigen::VectorXd tau(n);
  Json t = Json::array();
  std::vector<Json> joints(static_cast<std::size_t>(n), Json::array());
  for (const long i : indices) {
    robot::inverse_dynamics(model, data, limits.torque_layout, limits.torque_parameters, sampled.q.col(i),
                            sampled.qd.col(i), sampled.qdd.col(i), tau);
    t.push_back(sampled.t[i]);
    for (Eigen::Index k = 0; k < n; ++k) joints[static_cast<std::size_t>(k)].push_back(tau[k]);
  }
  return {{"t", t}, {"tau", joints}};
}

}  // namespace manipid::api

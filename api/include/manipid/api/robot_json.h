// robot_json.h — a rigid-body robot's identification as JSON: the object `manipid identify --robot --json`
// prints (and the service will return), and parameter vectors read back from it.
//
// Shape (numbers that do not exist are null, never NaN):
//   { "method": "input-error (linear least squares)",
//     "robot": {"name", "base_link", "tip_link", "joints": [{"name", "link", "type"}]},
//     "parameters": {"friction": ["viscous", ...], "armature": false},
//     "base_parameters": [{"name": "Izz1 + Iyy2 + ...", "combination", "estimate", "std_error", "relative_std_error",
//                          "data_share"}],
//     "correlation": [[...]]  (base × base),
//     "condition_number", "unexcited": [...],
//     "point": {"m1": ..., ..., "fv1": ...}   every standard parameter: the base estimate, nearest to the prior,
//     "prior": {...}                         the URDF's own values,
//     "unidentifiable": [...]                standard parameters no motion can determine,
//     "friction": [{"joint", "fv", "fc", "fo"}]   per joint, from point (only the layout's terms),
//     "filters": {"differentiation": {"half_length", "band", "dt", "cutoff_hz"},
//                 "comparison": {"lowpass", "cutoff_hz"}, "working_step", "trim_seconds"},
//     "selection": {"by_held_out", "ridge", "held_out_error",
//                   "candidates": [{"comparison_cutoff_hz", "friction", "ridge", "held_out_error"}]},
//     "judge": {"lowpass", "cutoff_hz", "trim_seconds"}   what "fit" and "validation" are judged under,
//     "torque_joints": [joint names fitted and judged], "runs", "rows",
//     "fit": {"residual_rms": [...], "relative_error": [...], "rms_error": [...], "overall_relative_error"},
//     "validation": {"relative_error": [...], "rms_error": [...], "overall_relative_error",
//                    "prior": {"relative_error": [...], "rms_error": [...], "overall_relative_error"}}  (if any),
//     "warnings": [...], "wall_seconds" }
#pragma once

#include "manipid/core/robot/excitation.h"
#include "manipid/core/robot/identification.h"
#include "manipid/core/robot/model.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace manipid::api {

/// What the service stores and shows of an uploaded robot (the robot resource without id, name and
/// times): {"robot_name", "base_link", "tip_link",
///   "joints": [{"name", "link", "type", "axis": [x, y, z], "limits": {"lower", "upper", "velocity",
///              "effort"}, "damping", "friction"}],
///   "links": [[the URDF links of body 1], ...],
///   "gravity": [gx, gy, gz],
///   "parameters": {"names": [...], "urdf_values": {...}}   (the default layout: viscous and Coulomb),
///   "options": {"friction": ["viscous", "coulomb", "offset"], "armature": true},
///   "base_parameters": {"count", "friction": ["viscous", "coulomb"]}   (for any excitation),
///   "warnings": [...]}
nlohmann::ordered_json robot_description(const robot::Model& model, const std::vector<std::string>& warnings);

/// An excitation design as JSON: the series' formula, period, harmonics, q0, a, b per joint, the start,
/// the criterion's value and the condition number, the target ("arm" or "payload") and the joints that moved, the layout, the limits (position, velocity,
/// acceleration, jerk, torque; null where none), per joint the peaks reached and the share of each limit
/// used ("peaks", "usage"), the torque's amplitude factor, the binding limits, the ramp from the start pose
/// (null without one), the seed, evaluations, time and why it stopped (what `manipid excitation --coefficients` writes and an excitation
/// job's result carries).
nlohmann::ordered_json excitation_to_json(const robot::Model& model, const robot::ExcitationOptions& options,
                                          const robot::ExcitationLimits& limits, const robot::ExcitationDesign& design);
/// The torque the limits' model predicts along a sampled excitation, at plot_indices (plots.h):
/// {"t": [...], "tau": [[joint 1 ...], ...]} (N m; N prismatic) — what the excitation page draws against the
/// torque limits.
nlohmann::ordered_json excitation_torque_json(const robot::Model& model, const robot::ExcitationLimits& limits,
                                              const robot::SampledExcitation& sampled, long max_points);

/// The friction terms a layout has, by name: "viscous", "coulomb", "offset".
std::vector<std::string> friction_names(const robot::ParameterLayout& layout);
/// "viscous,coulomb,offset" (any subset, any order; "none" for no friction) → the layout's friction
/// flags; throws InputError(field) for an unknown or repeated term.
void parse_friction(const std::vector<std::string>& terms, robot::ParameterLayout& layout, const std::string& field);

/// A prediction's figures: {"relative_error": [...], "rms_error": [...], "overall_relative_error"}.
nlohmann::ordered_json prediction_to_json(const robot::TorquePrediction& prediction);
/// What figures are judged under: {"lowpass", "cutoff_hz", "trim_seconds"}.
nlohmann::ordered_json judge_to_json(const JudgeOptions& judge);

nlohmann::ordered_json robot_result_to_json(const robot::Model& model, const robot::IdentificationResult& result,
                                            const std::optional<robot::ValidationReport>& validation);

/// The comment an identified URDF opens with (urdf_writer.h's note), from a robot identification's result
/// (robot_result_to_json's JSON) and where its runs came from ("train.csv", "datasets ds_1, ds_2"; may be
/// empty): how it was identified, what the data determine (base parameters, links), the judged errors.
std::string identified_urdf_note(const nlohmann::json& result, const std::string& sources);

/// A standard parameter vector for `model` from JSON: an identify result (its "point": the layout is
/// exactly its names') or a flat {"name": value} object (overrides on the URDF: its viscous and Coulomb
/// friction always, offsets fo* and rotor inertias Ia* when named; everything not named keeps the URDF's
/// value). Throws InputError(field) for unknown names or values that are not finite numbers.
struct ParameterValues {
  robot::ParameterLayout layout;
  Eigen::VectorXd values;
};
ParameterValues parameters_from_json(const robot::Model& model, const nlohmann::json& json, const std::string& field);

}  // namespace manipid::api

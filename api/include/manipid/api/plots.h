// plots.h — series for drawing: a trajectory in the upload's JSON shape, the torque fit of a
// finished identification (filtered measured torque beside the model torque at the estimate),
// and the evenly spaced sample indices both use to stay small. What the dashboard draws, and
// what a script plots (GET /v1/datasets/{id}/data, GET /v1/jobs/{id}/fit).
//
// Decimation is for drawing only: the stored data and histories are never thinned.
#pragma once

#include "manipid/core/robot/model.h"
#include "manipid/core/signal/trajectory.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace manipid::api {

/// Indices 0, s, 2s, … of `count` samples (s = thinning_stride, records.h), and always the last: at most
/// max_points + 1 of them, all of them when count ≤ max_points (or max_points ≤ 0).
std::vector<long> plot_indices(long count, long max_points);

/// The samples at plot_indices(samples, max_points): the whole trajectory when max_points ≤ 0.
Trajectory thin(const Trajectory& data, long max_points);

/// {"t": [...], "q": [[joint 1 ...], ...], "tau"?: [[...]], "ref"?: [[...]]} — the shape
/// POST /v1/datasets accepts, so it uploads back unchanged.
nlohmann::ordered_json trajectory_to_json(const Trajectory& data);

/// The fit at a finished identification's estimate (the result's "point"), from the job's
/// stored request and result and its dataset: {"parameters": {...}, "filter": {...}, "torque_source", "samples",
/// "t": [...], "joints": [{"joint", "measured": [...], "model": [...], "residual": [...],
/// "rms_measured", "rms_residual"}]}. The RMS figures use every sample, the series are
/// decimated to max_points. Throws InputError when request, result and data do not fit together.
nlohmann::ordered_json torque_fit_to_json(const std::string& request_json, const std::string& result_json,
                                          const Trajectory& data, long max_points);

/// The same for a URDF robot's identification (request with robot_id): the measured torque on `data` beside
/// the torque its "point" predicts, both through the result's judge (robot/prediction.h), per fitted joint,
/// with "relative_error" per joint and overall. With `prior`, also the URDF's own values' errors under "prior"
/// (the validation view). {"judge": {"lowpass", "cutoff_hz", "trim_seconds"}, "samples", "t", "joints":
/// [{"joint", "name", "measured", "model", "residual", "rms_measured", "rms_residual", "relative_error"}],
/// "overall_relative_error", "friction"?, "prior"?}. "friction", when the result estimated any of fv, fc, fo:
/// {"terms": ["viscous", "coulomb", "offset"] (those estimated), "joints": [{"joint", "name", "law": {"fv"?,
/// "fc"?, "fo"?}, "qd": [...], "torque": [...]}]} — per fitted joint, at the same instants as "t", the judge's
/// q̇ and what friction must explain: the measured torque less the prediction with fv, fc and fo set to 0
/// (the armature stays), both under the judge's low-pass; "law" the point's friction terms.
nlohmann::ordered_json robot_fit_to_json(const robot::Model& model, const std::string& request_json,
                                         const std::string& result_json, const Trajectory& data, long max_points,
                                         bool prior);

/// The same for a payload identification (payload_identification_from_json's request, a result with its
/// "arm_point"): the measured torque on `data` beside what the arm predicts with the payload ("model") and
/// without it ("arm_only" per joint, with "arm_only_relative_error"), both under the request's judge and on its
/// grid; "arm_only": {"relative_error", "rms_error", "overall_relative_error"} over the judged joints.
nlohmann::ordered_json payload_fit_to_json(const robot::Model& model, const std::string& request_json,
                                           const std::string& result_json, const Trajectory& data, long max_points);

}  // namespace manipid::api

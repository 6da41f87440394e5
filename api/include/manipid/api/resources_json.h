// resources_json.h — how datasets, jobs and cost histories look on the wire (JSON, and CSV for
// histories). The routes use these; so can anything else that must answer in the same shape.
#pragma once

#include "manipid/api/records.h"
#include "manipid/core/paper/presets.h"

#include <nlohmann/json.hpp>

#include <string>

namespace manipid::api {

/// {"id", "name", "created_at", "joints", "samples", "dt", "uniform", "has_torque", "has_reference",
///  "has_rates", "has_accelerations", "source_job" (null unless a simulation or excitation made it),
///  "links": {"self", "data"}}
nlohmann::ordered_json dataset_to_json(const DatasetInfo& dataset);

/// What job_to_text writes: the whole job, or a list's item (all but "request").
enum class JobText { whole, without_request };

/// The job as JSON text:
/// {"id", "kind", "state", "created_at", "started_at", "finished_at" (null until then),
///  "attempts", "worker" (HOST:PID while running, else null), "dataset_id" (null when none yet),
///  "robot_id", "validation_dataset_id" (null when none), "cancel_requested",
///  "progress": {"evaluations", "best_cost"}, "request": {...} (not in without_request),
///  "result": {...} (succeeded; also cancelled identifications: the best point reached),
///  "error": {problem} (failed), "links": {"self", "cancel", "history"?, "dataset"?, ...}}
/// Text, not a tree: a status read is the most frequent request, and the stored request and
/// result (kilobytes of JSON text written by manipid) are spliced in as they are rather than
/// parsed and written out again (most of a read's time before). Stored text that is not JSON
/// goes out as a string.
std::string job_to_text(const JobInfo& job, JobText form = JobText::whole);

/// {"id", "name", "created_at", the stored description (robot_json.h: robot_description's members),
///  "links": {"self", "urdf"}}
nlohmann::ordered_json robot_to_json(const RobotInfo& robot);

/// {"name", "description", "joints", "parameters": [m1..ln], "true_parameters": {...},
///  "initial_parameters": {...}, "kp", "kd", "reference": {"step_times", "amplitudes",
///  "half_length", "band"}, "simulation": {"duration", "dt"}, "kinetic_energy"}
nlohmann::ordered_json preset_to_json(const Preset& preset);

/// Parameter names for a θ of `size` entries: m1..mn, l1..ln.
std::vector<std::string> history_parameter_names(std::size_t size);
/// {"items": [{"index", "cost", "parameters": {"m1": ...}}], "next_page_token"?}
nlohmann::ordered_json history_page_to_json(const Page<HistoryEntry>& page);
/// {"total", "stride", "best_index" (null when empty), "items": [as in a page]}
nlohmann::ordered_json history_overview_to_json(const HistoryOverview& overview);
/// "index,cost,m1,...,ln" then one row per entry (the format `manipid identify --history` writes).
std::string history_to_csv(const std::vector<HistoryEntry>& entries);

}  // namespace manipid::api

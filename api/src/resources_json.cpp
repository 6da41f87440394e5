// resources_json.cpp — datasets, jobs and histories as JSON and CSV (resources_json.h).
#include "manipid/api/resources_json.h"
#include "json_numbers.h"

#include "manipid/api/csv.h"
#include "manipid/api/job_kinds.h"
#include "manipid/core/paper/model.h"

#include <cmath>

namespace manipid::api {
namespace {

using Json = nlohmann::ordered_json;
using json_numbers::number;

Json text_or_null(const std::string& text) { return text.empty() ? Json(nullptr) : Json(text); }

/// Stored JSON text back to JSON; text that does not parse (never written by manipid) is
/// passed on as a string rather than failing the whole response.
Json embedded(const std::string& text) {
  Json parsed = Json::parse(text, nullptr, false);
  return parsed.is_discarded() ? Json(text) : parsed;
}

}  // namespace

nlohmann::ordered_json dataset_to_json(const DatasetInfo& dataset) {
  const std::string self = "/v1/datasets/" + dataset.id;
  return {{"id", dataset.id},
          {"name", dataset.name},
          {"created_at", dataset.created_at},
          {"owner", text_or_null(dataset.owner)},
          {"joints", dataset.joints},
          {"samples", dataset.samples},
          {"dt", dataset.dt},
          {"uniform", dataset.uniform},
          {"has_torque", dataset.has_torque},
          {"has_reference", dataset.has_reference},
          {"has_rates", dataset.has_rates},
          {"has_accelerations", dataset.has_accelerations},
          {"source_job", text_or_null(dataset.source_job)},
          {"links", {{"self", self}, {"data", self + "?format=csv"}}}};
}

namespace {

/// Every member of a job up to "progress": what the store keeps in columns, not as JSON text.
Json job_head(const JobInfo& job) {
  return {{"id", job.id},
          {"kind", to_string(job.kind)},
          {"state", to_string(job.state)},
          {"created_at", job.created_at},
          {"owner", text_or_null(job.owner)},
          {"started_at", text_or_null(job.started_at)},
          {"finished_at", text_or_null(job.finished_at)},
          {"attempts", job.attempts},
          {"worker", job.state == JobState::running ? text_or_null(job.worker) : Json(nullptr)},
          {"dataset_id", text_or_null(job.dataset_id)},
          {"robot_id", text_or_null(job.robot_id)},
          {"validation_dataset_id", text_or_null(job.validation_dataset_id)},
          {"cancel_requested", job.cancel_requested},
          {"progress", {{"evaluations", job.evaluations}, {"best_cost", job.best_cost ? number(*job.best_cost) : Json(nullptr)}}}};
}

Json job_links(const JobInfo& job) {
  const std::string self = "/v1/jobs/" + job.id;
  const JobKindHandler& handler = job_kind_handler(job.kind);
  Json links = {{"self", self}, {"cancel", self + "/cancel"}};
  // Only the kinds that evaluate a cost step by step (the paper model's identifications) have a history.
  if (handler.has_history) links["history"] = self + "/history";
  if (!job.dataset_id.empty()) links["dataset"] = "/v1/datasets/" + job.dataset_id;
  if (handler.on_robot && !job.robot_id.empty()) links["robot"] = "/v1/robots/" + job.robot_id;
  if (!job.validation_dataset_id.empty()) links["validation_dataset"] = "/v1/datasets/" + job.validation_dataset_id;
  if (handler.has_validation && !job.validation_dataset_id.empty()) links["validation"] = self + "/validation";
  if (handler.has_fit) links["fit"] = self + "/fit";
  if (handler.writes_urdf) links["urdf"] = self + "/urdf";
  return links;
}

/// `,"name":` and the stored JSON text as it is (manipid wrote it with dump(): the bytes a parse
/// and dump would give back); text that is not JSON goes out as a string, as embedded() does.
void append_embedded(std::string& out, const char* name, const std::string& text) {
  out += ",\"";
  out += name;
  out += "\":";
  if (Json::accept(text)) {
    out += text;
  } else {
    out += Json(text).dump();
  }
}

}  // namespace

std::string job_to_text(const JobInfo& job, JobText form) {
  std::string out = job_head(job).dump();
  out.pop_back();  // the head's closing brace: the members below follow
  if (form == JobText::whole) append_embedded(out, "request", job.request);
  if (!job.result.empty()) append_embedded(out, "result", job.result);
  if (!job.error.empty()) append_embedded(out, "error", job.error);
  out += ",\"links\":";
  out += job_links(job).dump();
  out += '}';
  return out;
}

nlohmann::ordered_json robot_to_json(const RobotInfo& robot) {
  const std::string self = "/v1/robots/" + robot.id;
  Json json = {
      {"id", robot.id}, {"name", robot.name}, {"created_at", robot.created_at}, {"owner", text_or_null(robot.owner)}};
  // The description made at upload (robot_json.h: robot_description), stored as JSON text.
  const Json description = embedded(robot.summary);
  if (description.is_object()) {
    for (const auto& [key, value] : description.items()) json[key] = value;
  }
  json["links"] = {{"self", self}, {"urdf", self + "?format=urdf"}};
  return json;
}

nlohmann::ordered_json preset_to_json(const Preset& preset) {
  const std::vector<std::string> names = parameter_names(preset.model.joint_count());
  const auto by_name = [&names](const Parameters& parameters) {
    const Eigen::VectorXd theta = parameters.vector();
    Json values = Json::object();
    for (std::size_t i = 0; i < names.size(); ++i) values[names[i]] = theta[static_cast<Eigen::Index>(i)];
    return values;
  };
  const auto list = [](const Eigen::VectorXd& vector) { return std::vector<double>(vector.data(), vector.data() + vector.size()); };
  return {{"name", preset.name},
          {"description", preset.description},
          {"kinetic_energy", to_string(preset.model.kinetic_energy)},
          {"joints", preset.model.joint_count()},
          {"parameters", names},
          {"true_parameters", by_name(preset.true_parameters)},
          {"initial_parameters", by_name(preset.initial_parameters)},
          {"kp", list(preset.controller.kp)},
          {"kd", list(preset.controller.kd)},
          {"reference",
           {{"step_times", preset.reference.step_times},
            {"amplitudes", preset.reference.amplitudes},
            {"half_length", preset.reference.half_length},
            {"band", preset.reference.band}}},
          {"simulation", {{"duration", preset.simulation.duration}, {"dt", preset.simulation.dt}}}};
}

std::vector<std::string> history_parameter_names(std::size_t size) {
  return parameter_names(static_cast<int>(size / 2));
}

namespace {

Json history_items(const std::vector<HistoryEntry>& entries) {
  Json items = Json::array();
  for (const HistoryEntry& entry : entries) {
    const std::vector<std::string> names = history_parameter_names(entry.theta.size());
    Json parameters = Json::object();
    for (std::size_t i = 0; i < names.size() && i < entry.theta.size(); ++i) parameters[names[i]] = number(entry.theta[i]);
    items.push_back({{"index", entry.index}, {"cost", number(entry.cost)}, {"parameters", parameters}});
  }
  return items;
}

}  // namespace

nlohmann::ordered_json history_page_to_json(const Page<HistoryEntry>& page) {
  Json json = {{"items", history_items(page.items)}};
  if (!page.next_page_token.empty()) json["next_page_token"] = page.next_page_token;
  return json;
}

nlohmann::ordered_json history_overview_to_json(const HistoryOverview& overview) {
  return {{"total", overview.total},
          {"stride", overview.stride},
          {"best_index", overview.best_index ? Json(*overview.best_index) : Json(nullptr)},
          {"items", history_items(overview.items)}};
}

std::string history_to_csv(const std::vector<HistoryEntry>& entries) {
  CsvTable table;
  table.columns = {"index", "cost"};
  const std::size_t size = entries.empty() ? 0 : entries.front().theta.size();
  for (const std::string& name : history_parameter_names(size)) table.columns.push_back(name);
  table.data.resize(static_cast<Eigen::Index>(entries.size()), static_cast<Eigen::Index>(table.columns.size()));
  for (std::size_t r = 0; r < entries.size(); ++r) {
    const auto row = static_cast<Eigen::Index>(r);
    table.data(row, 0) = static_cast<double>(entries[r].index);
    table.data(row, 1) = entries[r].cost;
    for (std::size_t i = 0; i < size && i < entries[r].theta.size(); ++i) {
      table.data(row, static_cast<Eigen::Index>(2 + i)) = entries[r].theta[i];
    }
  }
  return format_csv(table);
}

}  // namespace manipid::api

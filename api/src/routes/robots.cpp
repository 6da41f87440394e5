// robots.cpp — the /v1/robots routes (upload a URDF as XML or JSON, list, the resource or the document
// back byte for byte, delete) and /v1/excitations (a job that designs a trajectory for a robot).
#include "manipid/api/problem.h"
#include "manipid/api/resources_json.h"
#include "manipid/api/robot_json.h"
#include "manipid/api/robot_requests.h"

#include "http/request_helpers.h"  // includes httplib.h, after the manipid headers
#include "http/responses.h"
#include "routes/handlers.h"

namespace manipid::api::http {

std::shared_ptr<const ParsedRobot> stored_robot(RouteState& state, const Caller& caller, const std::string& id,
                                                const std::string& field) {
  std::shared_ptr<const ParsedRobot> parsed = state.service.parsed_robot(caller, id);
  if (!parsed) throw ApiError(ProblemKind::invalid_field, "no robot " + id, field);
  return parsed;
}

void create_robot(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const auto key = idempotency_key(request);
  const std::string type = media_type(request);
  RobotUpload upload;
  // `curl --data-binary @arm.urdf` labels the body form-urlencoded unless told otherwise: an unlabelled
  // body is JSON when it looks like JSON, else the document.
  const bool unlabelled = type.empty() || type == "application/x-www-form-urlencoded";
  if (type == "application/xml" || type == "text/xml" || (unlabelled && !looks_like_json(request.body))) {
    // The document as the body; what JSON carries beside it comes as query parameters.
    upload.urdf = request.body;
    upload.name = request.get_param_value("name");
    upload.base = request.get_param_value("base");
    upload.tip = request.get_param_value("tip");
    require_utf8(upload.urdf, "urdf");
    require_utf8(upload.name, "name");
    require_utf8(upload.base, "base");
    require_utf8(upload.tip, "tip");
    if (upload.name.size() > 200) throw ApiError(ProblemKind::invalid_field, "name is longer than 200 bytes", "name");
  } else {
    upload = robot_from_json(json_body(request));  // refuses other media types with 415
  }
  auto parsed = std::make_shared<const ParsedRobot>(parse_robot(upload));  // kept for its jobs (robot_cache.h)
  if (upload.name.empty()) upload.name = parsed->model.name;
  const std::string description = robot_description(parsed->model, parsed->warnings).dump();
  const RobotCreated created = state.service.create_robot(caller, upload, parsed, description, key);
  response.set_header("Location", "/v1/robots/" + created.robot.id);
  if (created.replayed) response.set_header("Idempotent-Replayed", "true");
  send_json(response, 201, robot_to_json(created.robot));
}

void list_robots(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const Page<RobotInfo> page = state.service.robots(caller, page_request(request, 50));
  nlohmann::ordered_json items = nlohmann::ordered_json::array();
  for (const RobotInfo& robot : page.items) items.push_back(robot_to_json(robot));
  nlohmann::ordered_json body = {{"items", items}};
  if (!page.next_page_token.empty()) body["next_page_token"] = page.next_page_token;
  send_json(response, 200, body);
}

void get_robot(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  const std::string format = request.has_param("format") ? request.get_param_value("format") : "json";
  if (format != "json" && format != "urdf") {
    throw ApiError(ProblemKind::invalid_field, "format must be json or urdf, got '" + format + "'", "format");
  }
  if (format == "urdf") {
    const auto urdf = state.service.robot_urdf(caller, id);
    if (!urdf) throw ApiError(ProblemKind::not_found, "no robot " + id, "id");
    response.status = 200;
    response.set_content(*urdf, "application/xml");  // as uploaded, byte for byte
    return;
  }
  const auto robot = state.service.robot(caller, id);
  if (!robot) throw ApiError(ProblemKind::not_found, "no robot " + id, "id");
  send_json(response, 200, robot_to_json(*robot));
}

void delete_robot(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  switch (state.service.delete_robot(caller, id)) {
    case DeleteOutcome::deleted: response.status = 204; return;
    case DeleteOutcome::not_found: throw ApiError(ProblemKind::not_found, "no robot " + id, "id");
    case DeleteOutcome::conflict:
      throw ApiError(ProblemKind::conflict, "robot " + id + " is used by a queued or running job", "id");
  }
}

void submit_excitation(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  submit_job(state, request, response, [](const nlohmann::json&) { return JobKind::excitation; });
}

}  // namespace manipid::api::http

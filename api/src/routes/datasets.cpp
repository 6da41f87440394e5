// datasets.cpp — the /v1/datasets routes: upload (JSON or CSV), list, metadata or CSV data,
// the samples for drawing, delete.
#include "manipid/api/csv.h"
#include "manipid/api/plots.h"
#include "manipid/api/problem.h"
#include "manipid/api/requests.h"
#include "manipid/api/resources_json.h"

#include "http/request_helpers.h"  // includes httplib.h, after the manipid headers
#include "http/responses.h"
#include "routes/handlers.h"

namespace manipid::api::http {

void create_dataset(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const auto key = idempotency_key(request);
  const std::string type = media_type(request);
  // `curl --data-binary @run.csv` labels the body form-urlencoded unless told otherwise: an
  // unlabelled body is JSON when it looks like JSON, else CSV.
  const bool unlabelled = type.empty() || type == "application/x-www-form-urlencoded";
  DatasetUpload upload;
  if (type == "text/csv" || (unlabelled && !looks_like_json(request.body))) {
    upload = dataset_from_csv(request.body);
    upload.name = request.get_param_value("name");  // CSV has no room for it: ?name=
    if (upload.name.size() > 200) throw ApiError(ProblemKind::invalid_field, "name is longer than 200 bytes", "name");
  } else {
    upload = dataset_from_json(json_body(request));  // refuses other media types with 415
  }
  const DatasetCreated created = state.service.create_dataset(upload, key);
  response.set_header("Location", "/v1/datasets/" + created.dataset.id);
  if (created.replayed) response.set_header("Idempotent-Replayed", "true");
  send_json(response, 201, dataset_to_json(created.dataset));
}

void get_dataset(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const std::string id = request.matches[1];
  if (wants_csv(request)) {
    const auto data = state.service.dataset_data(id);
    if (!data) throw ApiError(ProblemKind::not_found, "no dataset " + id, "id");
    response.status = 200;
    response.set_content(format_csv(trajectory_to_csv(*data)), "text/csv");
    return;
  }
  const auto dataset = state.service.dataset(id);
  if (!dataset) throw ApiError(ProblemKind::not_found, "no dataset " + id, "id");
  send_json(response, 200, dataset_to_json(*dataset));
}

void get_dataset_data(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const std::string id = request.matches[1];
  const long max_points = max_points_parameter(request, 0);  // 0: every sample
  const auto data = state.service.dataset_data(id);
  if (!data) throw ApiError(ProblemKind::not_found, "no dataset " + id, "id");
  const Trajectory shown = thin(*data, max_points);
  if (wants_csv(request)) {
    response.status = 200;
    response.set_content(format_csv(trajectory_to_csv(shown)), "text/csv");
    return;
  }
  send_json(response, 200, trajectory_to_json(shown));
}

void list_datasets(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Page<DatasetInfo> page = state.service.datasets(page_request(request, 50));
  nlohmann::ordered_json items = nlohmann::ordered_json::array();
  for (const DatasetInfo& dataset : page.items) items.push_back(dataset_to_json(dataset));
  nlohmann::ordered_json body = {{"items", items}};
  if (!page.next_page_token.empty()) body["next_page_token"] = page.next_page_token;
  send_json(response, 200, body);
}

void delete_dataset(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const std::string id = request.matches[1];
  switch (state.service.delete_dataset(id)) {
    case DeleteOutcome::deleted: response.status = 204; return;
    case DeleteOutcome::not_found: throw ApiError(ProblemKind::not_found, "no dataset " + id, "id");
    case DeleteOutcome::conflict:
      throw ApiError(ProblemKind::conflict, "dataset " + id + " is the input of a queued or running job", "id");
  }
}

}  // namespace manipid::api::http

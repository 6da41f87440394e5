// datasets.cpp — the /v1/datasets routes: upload (JSON or CSV), list, metadata or CSV data,
// the samples for drawing, delete. A long dataset's samples are answered piece by piece.
#include "manipid/api/csv.h"
#include "manipid/api/plots.h"
#include "manipid/api/problem.h"
#include "manipid/api/records.h"
#include "manipid/api/requests.h"
#include "manipid/api/resources_json.h"

#include "http/request_helpers.h"  // includes httplib.h, after the manipid headers
#include "http/responses.h"
#include "routes/handlers.h"
#include "../json_numbers.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <utility>

namespace manipid::api::http {
namespace {

/// Samples per piece of an answer. A dataset longer than this is answered piece by piece as the
/// answer goes out (chunked), never built whole: a 10 M-sample dataset's JSON, built as one
/// document and string, took 1.8 GB for a 221 MB answer.
constexpr Eigen::Index samples_per_piece = 65'536;

/// Answers 200 with the pieces `next` appends to its string, as long as it says more follow.
void send_pieces(httplib::Response& response, const char* type, std::function<bool(std::string&)> next) {
  response.status = 200;
  response.set_chunked_content_provider(type, [next = std::move(next), more = true](std::size_t, httplib::DataSink& sink) mutable {
    std::string piece;
    if (more) more = next(piece);
    if (!piece.empty() && !sink.write(piece.data(), piece.size())) return false;
    if (!more) sink.done();
    return true;
  });
}

/// The rows [start, start + count) of every block.
Trajectory rows(const Trajectory& data, Eigen::Index start, Eigen::Index count) {
  const auto middle = [&](const Eigen::MatrixXd& block) {
    return block.cols() == 0 ? Eigen::MatrixXd() : Eigen::MatrixXd(block.middleRows(start, count));
  };
  Trajectory part;
  part.t = data.t.segment(start, count);
  part.q = middle(data.q);
  part.tau = middle(data.tau);
  part.ref = middle(data.ref);
  part.qd = middle(data.qd);
  part.qdd = middle(data.qdd);
  return part;
}

/// format_csv(trajectory_to_csv(data)), a piece of samples_per_piece rows at a time.
void send_csv(httplib::Response& response, std::shared_ptr<const Trajectory> data) {
  if (data->samples() <= samples_per_piece) {
    response.status = 200;
    response.set_content(format_csv(trajectory_to_csv(*data)), "text/csv");
    return;
  }
  send_pieces(response, "text/csv", [data, start = Eigen::Index{0}](std::string& piece) mutable {
    const Eigen::Index count = std::min<Eigen::Index>(samples_per_piece, data->samples() - start);
    piece = format_csv(trajectory_to_csv(rows(*data, start, count)));
    if (start > 0) piece.erase(0, piece.find('\n') + 1);  // the header once, at the start
    start += count;
    return start < data->samples();
  });
}

/// trajectory_to_json(data).dump(), a piece of samples_per_piece numbers at a time: the text
/// between the arrays as it is, each array's numbers as nlohmann writes them.
void send_json_samples(httplib::Response& response, std::shared_ptr<const Trajectory> data) {
  if (data->samples() <= samples_per_piece) {
    send_json(response, 200, trajectory_to_json(*data));
    return;
  }
  struct Part {
    std::string text;               ///< written as it is
    const double* values = nullptr;  ///< or these numbers, comma-separated
    Eigen::Index count = 0;
  };
  auto parts = std::make_shared<std::vector<Part>>();
  const Eigen::Index samples = data->samples();
  parts->push_back({"{\"t\":["});
  parts->push_back({"", data->t.data(), samples});
  parts->push_back({"]"});
  const auto block = [&](const char* name, const Eigen::MatrixXd& values) {
    if (values.cols() == 0) return;
    parts->push_back({std::string(",\"") + name + "\":["});
    for (Eigen::Index joint = 0; joint < values.cols(); ++joint) {
      parts->push_back({joint == 0 ? "[" : ",["});
      parts->push_back({"", values.col(joint).data(), samples});
      parts->push_back({"]"});
    }
    parts->push_back({"]"});
  };
  block("q", data->q);
  block("tau", data->tau);
  block("ref", data->ref);
  block("qd", data->qd);
  block("qdd", data->qdd);
  parts->push_back({"}"});
  send_pieces(response, "application/json",
              [data, parts, part = std::size_t{0}, offset = Eigen::Index{0}](std::string& piece) mutable {
                for (; part < parts->size() && !(*parts)[part].values; ++part) piece += (*parts)[part].text;
                if (part < parts->size()) {
                  const Part& numbers = (*parts)[part];
                  const Eigen::Index count = std::min<Eigen::Index>(samples_per_piece, numbers.count - offset);
                  nlohmann::ordered_json array = nlohmann::ordered_json::array();
                  for (Eigen::Index i = offset; i < offset + count; ++i) {
                    const double value = numbers.values[i];
                    array.push_back(json_numbers::number(value));
                  }
                  const std::string text = array.dump();
                  if (offset > 0) piece += ',';
                  piece.append(text, 1, text.size() - 2);
                  offset += count;
                  if (offset == numbers.count) {
                    ++part;
                    offset = 0;
                  }
                }
                return part < parts->size();
              });
}

}  // namespace

namespace {

/// At most how many numbers a CSV or JSON body holds: one more than its separators (',', '\n', '[').
std::size_t numbers_at_most(const std::string& body) {
  std::size_t separators = 0;
  for (const char c : body) separators += static_cast<std::size_t>(c == ',' || c == '\n' || c == '[');
  return separators + 1;
}

/// Tops the request's memory reservation up to what a text dataset of `body` takes at its peak
/// (memory_per_dataset_number per number it may hold): the pre-routing hook reserved
/// memory_per_body_byte per body byte, which a body of short numbers ("0,0,0,...") outgrows
/// eightfold. Refused before parsing: 413 when the budget could never hold it, 503 when not now.
void reserve_for_numbers(RouteState& state, const std::string& body) {
  const std::size_t numbers = numbers_at_most(body);
  const std::size_t need = body.size() + numbers * memory_per_dataset_number;
  if (need <= body.size() * memory_per_body_byte) return;  // what the hook reserved holds it
  const auto mib = [](std::size_t bytes) { return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB"; };
  const std::string what = "this body holds up to " + std::to_string(numbers) + " numbers, which take up to " +
                           mib(need) + " while parsed and stored (" + std::to_string(memory_per_dataset_number) +
                           " bytes each)";
  if (need > state.memory.budget()) {
    throw ApiError(ProblemKind::payload_too_large,
                   what + ", more than this server's --memory-budget (" + mib(state.memory.budget()) +
                       "): upload the run in shorter pieces, or ask for a larger --memory-budget",
                   "body");
  }
  if (!state.memory.reserve(need)) {
    throw ApiError(ProblemKind::memory_busy, what + ", and other requests hold the rest of --memory-budget now; try again later",
                   "body");
  }
}

}  // namespace

void create_dataset(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const auto key = idempotency_key(request);
  const std::string type = media_type(request);
  // `curl --data-binary @run.csv` labels the body form-urlencoded unless told otherwise: an
  // unlabelled body is JSON when it looks like JSON, else CSV.
  const bool unlabelled = type.empty() || type == "application/x-www-form-urlencoded";
  // What a bag's joints and a column map's {joint} match: the names of the robot the query names, if any.
  const auto robot_joint_names = [&] {
    std::vector<std::string> names;
    if (request.has_param("robot_id")) {
      const auto named = stored_robot(state, caller, request.get_param_value("robot_id"), "robot_id");
      for (const robot::Joint& joint : named->model.joints) {
        names.push_back(joint.name);
      }
    }
    return names;
  };
  DatasetUpload upload;
  const bool bag_type = type == "application/vnd.sqlite3" || type == "application/x-sqlite3";
  if (bag_type || ((unlabelled || type == "application/octet-stream") && is_sqlite_database(request.body))) {
    // A ROS 2 bag (sqlite3 storage) of JointState: its topic from the query, its joints by the robot's names.
    BagOptions options;
    options.topic = request.get_param_value("topic");
    options.joint_names = robot_joint_names();
    upload = dataset_from_bag(request.body, options);
    upload.name = request.get_param_value("name");
    require_utf8(upload.name, "name");
    if (upload.name.size() > 200) throw ApiError(ProblemKind::invalid_field, "name is longer than 200 bytes", "name");
  } else if (type == "text/csv" || (unlabelled && !looks_like_json(request.body))) {
    reserve_for_numbers(state, request.body);
    // A lab's own log: its column map and units from the query (and a robot's joint names for {joint}).
    LogFormat format;
    format.columns = request.get_param_value("columns");
    if (request.has_param("time_unit")) format.time_unit = request.get_param_value("time_unit");
    if (request.has_param("angle_unit")) format.angle_unit = request.get_param_value("angle_unit");
    format.joint_names = robot_joint_names();
    try {
      upload = dataset_from_csv(request.body, format);
    } catch (const InputError& error) {
      // `curl -d @run.csv` sends the file without its line ends: the whole table as one line.
      if (!unlabelled || request.body.find('\n') != std::string::npos) throw;
      throw InputError("body", "the body is one line (" + std::string(error.what()) + "): curl -d @file drops the file's "
                               "line ends; send it with curl --data-binary @run.csv -H 'Content-Type: text/csv'");
    }
    upload.name = request.get_param_value("name");  // CSV has no room for it: ?name=
    require_utf8(upload.name, "name");
    if (upload.name.size() > 200) throw ApiError(ProblemKind::invalid_field, "name is longer than 200 bytes", "name");
  } else {
    const auto text = json_text(request);  // refuses other media types with 415
    reserve_for_numbers(state, request.body);
    upload = dataset_from_json_text(text);  // no document of the body: numbers straight into arrays
  }
  const DatasetCreated created = state.service.create_dataset(caller, upload, key);
  response.set_header("Location", "/v1/datasets/" + created.dataset.id);
  if (created.replayed) response.set_header("Idempotent-Replayed", "true");
  send_json(response, 201, dataset_to_json(created.dataset));
}

void get_dataset(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  if (wants_csv(request)) {
    auto data = state.service.dataset_data(caller, id);
    if (!data) throw ApiError(ProblemKind::not_found, "no dataset " + id, "id");
    send_csv(response, std::make_shared<const Trajectory>(std::move(*data)));
    return;
  }
  const auto dataset = state.service.dataset(caller, id);
  if (!dataset) throw ApiError(ProblemKind::not_found, "no dataset " + id, "id");
  send_json(response, 200, dataset_to_json(*dataset));
}

void get_dataset_data(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  const long max_points = max_points_parameter(request, 0);  // 0: every sample
  auto data = state.service.dataset_data(caller, id);
  if (!data) throw ApiError(ProblemKind::not_found, "no dataset " + id, "id");
  // Every sample: the stored data itself, not a copy.
  auto shown = std::make_shared<const Trajectory>(thinning_stride(data->samples(), max_points) == 1
                                                      ? std::move(*data)
                                                      : thin(*data, max_points));
  data.reset();
  if (wants_csv(request)) {
    send_csv(response, std::move(shown));
  } else {
    send_json_samples(response, std::move(shown));
  }
}

void list_datasets(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const Page<DatasetInfo> page = state.service.datasets(caller, page_request(request, 50));
  nlohmann::ordered_json items = nlohmann::ordered_json::array();
  for (const DatasetInfo& dataset : page.items) items.push_back(dataset_to_json(dataset));
  nlohmann::ordered_json body = {{"items", items}};
  if (!page.next_page_token.empty()) body["next_page_token"] = page.next_page_token;
  send_json(response, 200, body);
}

void delete_dataset(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  switch (state.service.delete_dataset(caller, id)) {
    case DeleteOutcome::deleted: response.status = 204; return;
    case DeleteOutcome::not_found: throw ApiError(ProblemKind::not_found, "no dataset " + id, "id");
    case DeleteOutcome::conflict:
      throw ApiError(ProblemKind::conflict, "dataset " + id + " is the input of a queued or running job", "id");
  }
}

}  // namespace manipid::api::http

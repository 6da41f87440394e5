// jobs.cpp — the /v1/jobs routes: list, state (long-poll, ETag), cost history (pages, CSV,
// thinned for drawing), torque fit, validation, the URDF with a result written in, cancel, delete.
#include "manipid/api/job_kinds.h"
#include "manipid/api/problem.h"
#include "manipid/api/resources_json.h"
#include "manipid/api/robot_json.h"
#include "manipid/api/robot_requests.h"

#include "http/request_helpers.h"  // includes httplib.h, after the manipid headers
#include "http/responses.h"
#include "routes/handlers.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <vector>

namespace manipid::api::http {

void send_job(httplib::Response& response, int status, const JobInfo& job) {
  response.status = status;
  response.set_content(job_to_text(job), "application/json");
  if (!is_terminal(job.state)) response.set_header("Retry-After", "1");
}

void get_job(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  std::optional<JobInfo> job;
  if (request.has_param("wait")) {
    const std::string text = request.get_param_value("wait");
    double seconds = 0.0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), seconds);
    if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(seconds) || seconds < 0) {
      throw ApiError(ProblemKind::invalid_field, "wait must be a number of seconds >= 0, got '" + text + "'", "wait");
    }
    seconds = std::min(seconds, state.options.max_wait_seconds);
    // A waiter holds this HTTP thread: at most max_waiters at once, so /healthz, uploads and
    // reads always find a thread; the others get the job as it stands and come back later.
    if (seconds <= 0) {
      job = state.service.wait(caller, id, 0.0);
    } else if (state.waiters.fetch_add(1) >= state.options.max_waiters) {
      state.waiters.fetch_sub(1);
      response.set_header("Manipid-Wait", "declined");
      job = state.service.job(caller, id);
    } else {
      struct Release {
        std::atomic<int>& count;
        ~Release() { count.fetch_sub(1); }
      } release{state.waiters};
      job = state.service.wait(caller, id, seconds);
    }
  } else {
    job = state.service.job(caller, id);
  }
  if (!job) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
  const std::string body = job_to_text(*job);
  const std::string etag = etag_of(body);
  response.set_header("ETag", etag);
  if (!is_terminal(job->state)) response.set_header("Retry-After", "1");
  if (request.get_header_value("If-None-Match") == etag) {
    response.status = 304;
    return;
  }
  response.status = 200;
  response.set_content(body, "application/json");
}

void list_jobs(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  JobFilter filter;
  if (request.has_param("state")) {
    filter.state = parse_job_state(request.get_param_value("state"));
    if (!filter.state) {
      throw ApiError(ProblemKind::invalid_field,
                     "state must be queued, running, succeeded, failed or cancelled, got '" +
                         request.get_param_value("state") + "'",
                     "state");
    }
  }
  if (request.has_param("kind")) {
    filter.kind = parse_job_kind(request.get_param_value("kind"));
    if (!filter.kind) {
      std::string kinds;
      for (const JobKind kind : kJobKinds) kinds += std::string(kinds.empty() ? "" : ", ") + to_string(kind);
      throw ApiError(ProblemKind::invalid_field, "kind must be one of " + kinds + ", got '" + request.get_param_value("kind") + "'",
                     "kind");
    }
  }
  if (request.has_param("robot_id")) {
    filter.robot_id = request.get_param_value("robot_id");
    if (filter.robot_id.empty() || filter.robot_id.size() > 64) {
      throw ApiError(ProblemKind::invalid_field, "robot_id must be a robot's id (1 to 64 characters)", "robot_id");
    }
  }
  const Page<JobInfo> page = state.service.jobs(caller, filter, page_request(request, 50));
  std::string body = "{\"items\":[";
  for (const JobInfo& job : page.items) {
    if (&job != &page.items.front()) body += ',';
    body += job_to_text(job, JobText::without_request);  // lists stay light; GET the job for the whole of it
  }
  body += ']';
  if (!page.next_page_token.empty()) body += ",\"next_page_token\":" + nlohmann::ordered_json(page.next_page_token).dump();
  body += '}';
  response.status = 200;
  response.set_content(body, "application/json");
}

void job_history(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  if (request.has_param("max_points")) {
    // Thinned for drawing; paging does not apply.
    if (request.has_param("page_size") || request.has_param("page_token")) {
      throw ApiError(ProblemKind::invalid_field, "max_points cannot be combined with page_size or page_token", "max_points");
    }
    const auto overview = state.service.history_overview(caller, id, max_points_parameter(request, 0));
    if (!overview) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
    if (wants_csv(request)) {
      response.status = 200;
      response.set_content(history_to_csv(overview->items), "text/csv");
      return;
    }
    send_json(response, 200, history_overview_to_json(*overview));
    return;
  }
  if (wants_csv(request) && !request.has_param("page_size") && !request.has_param("page_token")) {
    // CSV without paging parameters: the whole history, as `manipid identify --history` writes it.
    std::vector<HistoryEntry> entries;
    PageRequest page{1000, ""};
    for (;;) {
      const auto chunk = state.service.history(caller, id, page);
      if (!chunk) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
      entries.insert(entries.end(), chunk->items.begin(), chunk->items.end());
      if (chunk->next_page_token.empty()) break;
      page.page_token = chunk->next_page_token;
    }
    response.status = 200;
    response.set_content(history_to_csv(entries), "text/csv");
    return;
  }
  const auto page = state.service.history(caller, id, page_request(request, 1000));
  if (!page) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
  if (wants_csv(request)) {
    if (!page->next_page_token.empty()) response.set_header("X-Next-Page-Token", page->next_page_token);
    response.status = 200;
    response.set_content(history_to_csv(page->items), "text/csv");
    return;
  }
  send_json(response, 200, history_page_to_json(*page));
}

namespace {

/// The robot a robot identification ran on, parsed as the job parsed it.
std::shared_ptr<const ParsedRobot> job_robot(RouteState& state, const Caller& caller, const JobInfo& job) {
  std::shared_ptr<const ParsedRobot> parsed = state.service.parsed_robot(caller, job.robot_id);
  if (!parsed) throw ApiError(ProblemKind::conflict, "the robot of job " + job.id + " was deleted", "robot_id");
  return parsed;
}

}  // namespace

namespace {

/// The fit of `job` on `data` by its kind's entry (job_kinds.h): its robot parsed as the job parsed it, when it
/// has one. A stored result that does not fit the request and data is a conflict, not the server's fault.
nlohmann::ordered_json fit_of(RouteState& state, const Caller& caller, const JobInfo& job, const Trajectory& data,
                              long max_points, bool validation) {
  const JobKindHandler& handler = job_kind_handler(job.kind);
  try {
    const std::shared_ptr<const ParsedRobot> robot = handler.on_robot ? job_robot(state, caller, job) : nullptr;
    return handler.fit({job, data, max_points, validation, robot ? &robot->model : nullptr});
  } catch (const nlohmann::json::exception&) {
    throw ApiError(ProblemKind::conflict, "job " + job.id + " has no usable stored result", "id");
  } catch (const InputError&) {
    throw ApiError(ProblemKind::conflict, "job " + job.id + " has no usable stored result", "id");
  }
}

}  // namespace

void job_fit(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  const long max_points = max_points_parameter(request, 2000);
  const auto job = state.service.job(caller, id);
  if (!job) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
  if (!job_kind_handler(job->kind).has_fit) {
    throw ApiError(ProblemKind::conflict, "job " + id + " is " + kind_with_article(job->kind) + "; only identifications have a fit",
                   "id");
  }
  if (job->result.empty()) {
    throw ApiError(ProblemKind::conflict,
                   "job " + id + " is " + to_string(job->state) + " and has no estimate to fit yet", "id");
  }
  const auto data = state.service.dataset_data(caller, job->dataset_id);
  if (!data) throw ApiError(ProblemKind::conflict, "the dataset of job " + id + " was deleted", "dataset_id");
  send_json(response, 200, fit_of(state, caller, *job, *data, max_points, false));
}

void job_validation(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  const long max_points = max_points_parameter(request, 2000);
  const auto job = state.service.job(caller, id);
  if (!job) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
  if (!job_kind_handler(job->kind).has_validation || job->validation_dataset_id.empty()) {
    throw ApiError(ProblemKind::conflict,
                   "job " + id + " has no validation run: only a robot or payload identification with a "
                   "validation_dataset_id has one",
                   "id");
  }
  if (job->state != JobState::succeeded) {
    throw ApiError(ProblemKind::conflict, "job " + id + " is " + to_string(job->state) + " and has no estimate yet", "id");
  }
  const auto data = state.service.dataset_data(caller, job->validation_dataset_id);
  if (!data) {
    throw ApiError(ProblemKind::conflict, "the validation dataset of job " + id + " was deleted", "validation_dataset_id");
  }
  send_json(response, 200, fit_of(state, caller, *job, *data, max_points, true));
}

void job_urdf(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  const auto job = state.service.job(caller, id);
  if (!job) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
  const JobKindHandler& handler = job_kind_handler(job->kind);
  if (!handler.writes_urdf || job->state != JobState::succeeded) {
    throw ApiError(ProblemKind::conflict,
                   "job " + id + " is not a succeeded robot or payload identification: nothing to write into a URDF", "id");
  }
  const auto robot = state.service.robot(caller, job->robot_id);
  const auto urdf = state.service.robot_urdf(caller, job->robot_id);
  if (!robot || !urdf) throw ApiError(ProblemKind::conflict, "the robot of job " + id + " was deleted", "robot_id");
  const std::shared_ptr<const ParsedRobot> stored = job_robot(state, caller, *job);
  UrdfDocument document;
  try {
    document = handler.urdf({*job, *urdf, stored->model});
  } catch (const nlohmann::json::exception&) {
    throw ApiError(ProblemKind::conflict, "job " + id + " has no usable stored result", "id");
  } catch (const InputError&) {
    throw ApiError(ProblemKind::conflict, "job " + id + " has no usable stored result", "id");
  }
  response.status = 200;
  response.set_content(document.text, "application/xml");
  // The name is the user's: only letters, digits, '.', '_' and '-' reach the header.
  std::string file = robot->name;
  for (char& c : file) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') c = '_';
  }
  response.set_header("Content-Disposition", "attachment; filename=\"" + file + "-" + document.suffix + ".urdf\"");
}

void cancel_job_with_id(RouteState& state, const Caller& caller, const std::string& id, httplib::Response& response) {
  const auto job = state.service.cancel(caller, id);
  if (!job) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
  send_job(response, 200, *job);
}

void cancel_job(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  cancel_job_with_id(state, caller, request.matches[1], response);
}

std::string cancel_route_id(const std::string& path) {
  const std::string prefix = "/v1/jobs/";
  if (path.rfind(prefix, 0) != 0) return "";
  std::size_t end = prefix.size();
  while (end < path.size() && (std::isalnum(static_cast<unsigned char>(path[end])) || path[end] == '_' || path[end] == '-')) ++end;
  const std::size_t length = end - prefix.size();
  const std::string rest = path.substr(end);
  if (length == 0 || length > 64 || (rest != "/cancel" && rest != ":cancel")) return "";
  return path.substr(prefix.size(), length);
}

void delete_job(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const std::string id = request.matches[1];
  switch (state.service.delete_job(caller, id)) {
    case DeleteOutcome::deleted: response.status = 204; return;
    case DeleteOutcome::not_found: throw ApiError(ProblemKind::not_found, "no job " + id, "id");
    case DeleteOutcome::conflict:
      throw ApiError(ProblemKind::conflict, "job " + id + " is queued or running; cancel it first", "id");
  }
}

}  // namespace manipid::api::http

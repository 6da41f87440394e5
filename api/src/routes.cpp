// routes.cpp — the HTTP routes of `manipid serve` (routes.h). Each handler maps the request to
// a Service call and the answer back; everything that can go wrong is an ApiError or an
// InputError turned into problem+json by `guarded`, so a bad request can never take the
// server down or leave half a change behind.
//
// The manipid headers come before httplib.h on purpose: Debian's httplib.h pulls in
// <resolv.h>, whose `_res` macro breaks Eigen if Eigen comes second.
#include "manipid/api/dashboard.h"
#include "manipid/api/plots.h"
#include "manipid/api/problem.h"
#include "manipid/api/requests.h"
#include "manipid/api/resources_json.h"
#include "manipid/api/routes.h"
#include "manipid/api/csv.h"

#include <httplib.h>
#include <openssl/evp.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>

namespace manipid::api {
namespace {

using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr const char* id_pattern = "([A-Za-z0-9_-]{1,64})";

/// Shared by every handler; lives as long as the server's handlers (captured by shared_ptr).
struct RouteState {
  RouteState(Service& service_, RouteOptions options_) : service(service_), options(std::move(options_)) {}
  Service& service;
  RouteOptions options;
  std::weak_ptr<RouteState> self;  ///< for handlers called from the pre-routing hook
  std::mutex mutex;
  std::map<std::string, long> requests;  ///< "METHOD,status" → count
};

thread_local Clock::time_point request_started;

// ---- Responses ---------------------------------------------------------------------------

void send_json(httplib::Response& response, int status, const nlohmann::ordered_json& body) {
  response.status = status;
  response.set_content(body.dump(), "application/json");
}

void send_problem(httplib::Response& response, const Problem& problem, const std::string& instance) {
  response.status = status_of(problem.kind);
  response.set_content(problem_to_json(problem, instance).dump(), "application/problem+json");
  if (problem.kind == ProblemKind::queue_full || problem.kind == ProblemKind::shutting_down) {
    response.set_header("Retry-After", "5");
  }
  if (problem.kind == ProblemKind::unauthorized) response.set_header("WWW-Authenticate", "Bearer");
}

/// Runs a handler; every failure becomes a problem+json answer (internal details only in the log).
template <class Handler>
httplib::Server::Handler guarded(std::shared_ptr<RouteState> state, Handler handler) {
  return [state, handler](const httplib::Request& request, httplib::Response& response) {
    try {
      handler(request, response);
    } catch (const ApiError& error) {
      send_problem(response, error.problem(), request.path);
    } catch (const InputError& error) {
      send_problem(response, problem_from(error), request.path);
    } catch (const std::bad_alloc&) {
      send_problem(response, {ProblemKind::internal, "out of memory while handling the request", ""}, request.path);
    } catch (const std::exception& error) {
      if (state->options.log) state->options.log(std::string("internal error on ") + request.path + ": " + error.what());
      send_problem(response, {ProblemKind::internal, "internal error; see the server log", ""}, request.path);
    }
  };
}

// ---- Requests ----------------------------------------------------------------------------

std::string media_type(const httplib::Request& request) {
  std::string type = request.get_header_value("Content-Type");
  type = type.substr(0, type.find(';'));
  type.erase(std::remove_if(type.begin(), type.end(), [](unsigned char c) { return std::isspace(c); }), type.end());
  std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return std::tolower(c); });
  return type;
}

bool looks_like_json(const std::string& body) {
  const auto first = body.find_first_not_of(" \t\r\n");
  return first != std::string::npos && (body[first] == '{' || body[first] == '[');
}

/// The body as a JSON object. Accepts application/json, and — because `curl -d @file` sends
/// application/x-www-form-urlencoded unless told otherwise — an unlabelled body that is JSON.
Json json_body(const httplib::Request& request) {
  const std::string type = media_type(request);
  if (!(type == "application/json" || type.empty() || type == "application/x-www-form-urlencoded" ||
        (type.size() > 5 && type.compare(type.size() - 5, 5, "+json") == 0))) {
    throw ApiError(ProblemKind::unsupported_media, "expected Content-Type application/json, got " + type, "Content-Type");
  }
  if (request.body.empty()) throw ApiError(ProblemKind::malformed_body, "the request body is empty; expected a JSON object", "body");
  Json body;
  try {
    body = Json::parse(request.body);
  } catch (const Json::exception& error) {  // parse_error, and out_of_range for 1e400
    std::string message = error.what();
    if (const auto colon = message.find("parse error"); colon != std::string::npos) message = message.substr(colon);
    throw ApiError(ProblemKind::malformed_body, "the body is not valid JSON: " + message, "body");
  }
  if (!body.is_object()) throw ApiError(ProblemKind::malformed_body, "expected a JSON object at the top level", "body");
  return body;
}

std::string sha256_hex(const std::string& text) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_Digest(text.data(), text.size(), digest, &length, EVP_sha256(), nullptr) != 1) {
    throw std::runtime_error("SHA-256 failed");
  }
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < length; ++i) {
    out += hex[digest[i] >> 4];
    out += hex[digest[i] & 15];
  }
  return out;
}

/// The Idempotency-Key header (printable ASCII, 1..255 characters) with the fingerprint of
/// the request it came with: the same key with a different body is refused (422).
std::optional<IdempotencyKey> idempotency_key(const httplib::Request& request) {
  if (!request.has_header("Idempotency-Key")) return std::nullopt;
  std::string key = request.get_header_value("Idempotency-Key");
  if (key.size() >= 2 && key.front() == '"' && key.back() == '"') key = key.substr(1, key.size() - 2);  // sf-string
  const bool printable = std::all_of(key.begin(), key.end(), [](unsigned char c) { return c > 32 && c < 127; });
  if (key.empty() || key.size() > 255 || !printable) {
    throw ApiError(ProblemKind::invalid_field, "Idempotency-Key must be 1 to 255 printable ASCII characters without spaces",
                   "Idempotency-Key");
  }
  return IdempotencyKey{key, sha256_hex(request.method + " " + request.path + "\n" + media_type(request) + "\n" + request.body)};
}

long long integer_parameter(const httplib::Request& request, const std::string& name, long long fallback,
                            long long lowest, long long highest) {
  if (!request.has_param(name)) return fallback;
  const std::string text = request.get_param_value(name);
  long long value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || value < lowest || value > highest) {
    throw ApiError(ProblemKind::invalid_field,
                   name + " must be an integer from " + std::to_string(lowest) + " to " + std::to_string(highest) +
                       ", got '" + text + "'",
                   name);
  }
  return value;
}

PageRequest page_request(const httplib::Request& request, int default_size) {
  PageRequest page;
  // AIP-158: 0 means the default; sizes above the maximum are coerced down by the store.
  page.page_size = static_cast<int>(integer_parameter(request, "page_size", default_size, 0, 1'000'000));
  if (page.page_size == 0) page.page_size = default_size;
  page.page_token = request.get_param_value("page_token");
  return page;
}

/// ?max_points= for the drawing endpoints: at most this many points (about), 2 to 1,000,000.
long max_points_parameter(const httplib::Request& request, long fallback) {
  return static_cast<long>(integer_parameter(request, "max_points", fallback, 2, 1'000'000));
}

bool wants_csv(const httplib::Request& request) {
  if (request.has_param("format")) {
    const std::string format = request.get_param_value("format");
    if (format == "csv") return true;
    if (format == "json") return false;
    throw ApiError(ProblemKind::invalid_field, "format must be csv or json, got '" + format + "'", "format");
  }
  return request.get_header_value("Accept").find("text/csv") != std::string::npos;
}

std::string etag_of(const std::string& body) { return "\"" + sha256_hex(body).substr(0, 32) + "\""; }

// ---- Handlers ----------------------------------------------------------------------------

void send_job(httplib::Response& response, int status, const JobInfo& job) {
  send_json(response, status, job_to_json(job));
  if (!is_terminal(job.state)) response.set_header("Retry-After", "1");
}

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

void submit(RouteState& state, const httplib::Request& request, httplib::Response& response, JobKind kind) {
  const auto key = idempotency_key(request);
  const Json body = json_body(request);
  std::string dataset_id;
  if (kind == JobKind::simulation) {
    (void)simulation_from_json(body);  // validates; the worker parses the stored text again
  } else {
    const IdentificationSpec spec = identification_from_json(body);
    if (spec.simulation) {
      const SimulationOptions& run = spec.simulation->preset.simulation;
      const int samples = static_cast<int>(std::floor(run.duration / run.dt + 1e-9)) + 1;
      check_against_data(spec, spec.simulation->preset.model.joint_count(), samples, true, true);
    } else {
      dataset_id = spec.dataset_id;
      const auto dataset = state.service.dataset(dataset_id);
      if (!dataset) throw ApiError(ProblemKind::invalid_field, "no dataset " + dataset_id, "dataset_id");
      check_against_data(spec, dataset->joints, dataset->samples, dataset->has_torque, dataset->has_reference);
    }
  }
  const SubmitResult submitted = state.service.submit({kind, body.dump(), dataset_id, "", ""}, key);
  response.set_header("Location", "/v1/jobs/" + submitted.job.id);
  if (submitted.replayed) response.set_header("Idempotent-Replayed", "true");
  send_job(response, 202, submitted.job);
}

void get_job(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const std::string id = request.matches[1];
  std::optional<JobInfo> job;
  if (request.has_param("wait")) {
    const std::string text = request.get_param_value("wait");
    double seconds = 0.0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), seconds);
    if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(seconds) || seconds < 0) {
      throw ApiError(ProblemKind::invalid_field, "wait must be a number of seconds >= 0, got '" + text + "'", "wait");
    }
    job = state.service.wait(id, std::min(seconds, state.options.max_wait_seconds));
  } else {
    job = state.service.job(id);
  }
  if (!job) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
  const std::string body = job_to_json(*job).dump();
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
      throw ApiError(ProblemKind::invalid_field,
                     "kind must be simulation or identification, got '" + request.get_param_value("kind") + "'", "kind");
    }
  }
  const Page<JobInfo> page = state.service.jobs(filter, page_request(request, 50));
  nlohmann::ordered_json items = nlohmann::ordered_json::array();
  for (const JobInfo& job : page.items) {
    nlohmann::ordered_json json = job_to_json(job);
    json.erase("request");  // lists stay light; GET the job for the whole of it
    items.push_back(std::move(json));
  }
  nlohmann::ordered_json body = {{"items", items}};
  if (!page.next_page_token.empty()) body["next_page_token"] = page.next_page_token;
  send_json(response, 200, body);
}

void job_history(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const std::string id = request.matches[1];
  if (request.has_param("max_points")) {
    // Thinned for drawing; paging does not apply.
    if (request.has_param("page_size") || request.has_param("page_token")) {
      throw ApiError(ProblemKind::invalid_field, "max_points cannot be combined with page_size or page_token", "max_points");
    }
    const auto overview = state.service.history_overview(id, max_points_parameter(request, 0));
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
      const auto chunk = state.service.history(id, page);
      if (!chunk) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
      entries.insert(entries.end(), chunk->items.begin(), chunk->items.end());
      if (chunk->next_page_token.empty()) break;
      page.page_token = chunk->next_page_token;
    }
    response.status = 200;
    response.set_content(history_to_csv(entries), "text/csv");
    return;
  }
  const auto page = state.service.history(id, page_request(request, 1000));
  if (!page) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
  if (wants_csv(request)) {
    if (!page->next_page_token.empty()) response.set_header("X-Next-Page-Token", page->next_page_token);
    response.status = 200;
    response.set_content(history_to_csv(page->items), "text/csv");
    return;
  }
  send_json(response, 200, history_page_to_json(*page));
}

void job_fit(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const std::string id = request.matches[1];
  const long max_points = max_points_parameter(request, 2000);
  const auto job = state.service.job(id);
  if (!job) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
  if (job->kind != JobKind::identification) {
    throw ApiError(ProblemKind::conflict, "job " + id + " is a simulation; only identifications have a fit", "id");
  }
  if (job->result.empty()) {
    throw ApiError(ProblemKind::conflict,
                   "job " + id + " is " + to_string(job->state) + " and has no estimate to fit yet", "id");
  }
  const auto data = state.service.dataset_data(job->dataset_id);
  if (!data) throw ApiError(ProblemKind::conflict, "the dataset of job " + id + " was deleted", "dataset_id");
  try {
    send_json(response, 200, torque_fit_to_json(job->request, job->result, *data, max_points));
  } catch (const nlohmann::json::exception&) {
    throw ApiError(ProblemKind::conflict, "job " + id + " has no usable stored result", "id");
  }
}

void list_presets(RouteState&, const httplib::Request&, httplib::Response& response) {
  nlohmann::ordered_json items = nlohmann::ordered_json::array();
  for (const std::string& name : preset_names()) items.push_back(preset_to_json(find_preset(name)));
  send_json(response, 200, {{"items", items}});
}

void get_preset(RouteState&, const httplib::Request& request, httplib::Response& response) {
  const std::string name = request.matches[1];
  const KineticEnergy energy = request.has_param("kinetic_energy")
                                   ? parse_kinetic_energy(request.get_param_value("kinetic_energy"), "kinetic_energy")
                                   : KineticEnergy::complete;
  const Preset preset = [&] {
    try {
      return find_preset(name, energy);
    } catch (const InputError& error) {  // an unknown name: it lists the known ones
      throw ApiError(ProblemKind::not_found, error.what(), "name");
    }
  }();
  send_json(response, 200, preset_to_json(preset));
}

void cancel_job_with_id(RouteState& state, const std::string& id, httplib::Response& response) {
  const auto job = state.service.cancel(id);
  if (!job) throw ApiError(ProblemKind::not_found, "no job " + id, "id");
  send_job(response, 200, *job);
}

void cancel_job(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  cancel_job_with_id(state, request.matches[1], response);
}

/// The job id of "/v1/jobs/{id}/cancel" or "/v1/jobs/{id}:cancel", else empty.
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
  const std::string id = request.matches[1];
  switch (state.service.delete_job(id)) {
    case DeleteOutcome::deleted: response.status = 204; return;
    case DeleteOutcome::not_found: throw ApiError(ProblemKind::not_found, "no job " + id, "id");
    case DeleteOutcome::conflict:
      throw ApiError(ProblemKind::conflict, "job " + id + " is queued or running; cancel it first", "id");
  }
}

std::string request_metrics(RouteState& state) {
  std::ostringstream out;
  out << "# HELP manipid_http_requests_total HTTP requests answered, by method and status.\n"
         "# TYPE manipid_http_requests_total counter\n";
  std::lock_guard lock(state.mutex);
  for (const auto& [key, count] : state.requests) {
    const auto comma = key.find(',');
    out << "manipid_http_requests_total{method=\"" << key.substr(0, comma) << "\",status=\"" << key.substr(comma + 1)
        << "\"} " << count << "\n";
  }
  return out.str();
}

void send_asset(httplib::Response& response, const std::string& path) {
  const auto& assets = dashboard_assets();
  const auto found = std::find_if(assets.begin(), assets.end(), [&path](const DashboardAsset& asset) { return asset.path == path; });
  if (found == assets.end()) throw ApiError(ProblemKind::not_found, "no file " + path, "path");
  // Embedded in this binary: revalidate on every load, so a new build is never mixed with an old cache.
  response.set_header("Cache-Control", "no-cache");
  response.set_header("X-Content-Type-Options", "nosniff");
  if (path == "/") {
    response.set_header("Content-Security-Policy",
                        "default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; frame-ancestors 'none'");
  }
  response.status = 200;
  response.set_content(std::string(found->body), std::string(found->content_type).c_str());
}

// ---- Cross-cutting -----------------------------------------------------------------------

bool token_matches(const std::string& given, const std::string& expected) {
  // Constant time in the token's content, so the comparison leaks nothing but the length.
  if (given.size() != expected.size()) return false;
  unsigned char difference = 0;
  for (std::size_t i = 0; i < given.size(); ++i) difference |= static_cast<unsigned char>(given[i] ^ expected[i]);
  return difference == 0;
}

/// Debian's cpp-httplib 0.11.4 answers "Accept-Encoding: br" (every browser sends it) with
/// Brotli at quality 11: 25 s of one server thread for a 17.7 MB history CSV, 0.6 s for the
/// dashboard's 0.5 MB history view. gzip does the same in 0.26 s and 60 ms. So the server
/// offers gzip only: "br" is struck from the request's Accept-Encoding before httplib reads it
/// to choose. (The Request is httplib's own non-const object, passed on as const.)
void refuse_brotli(const httplib::Request& request) {
  auto& headers = const_cast<httplib::Request&>(request).headers;
  auto [first, last] = headers.equal_range("Accept-Encoding");
  for (auto header = first; header != last; ++header) {
    std::string kept;
    std::stringstream codings(header->second);
    for (std::string coding; std::getline(codings, coding, ',');) {
      const auto start = coding.find_first_not_of(" \t");
      if (start == std::string::npos) continue;
      std::string name = coding.substr(start, coding.find_first_of(" \t;", start) - start);
      std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      if (name == "br") continue;
      kept += (kept.empty() ? "" : ", ") + coding.substr(start);
    }
    header->second = kept;
  }
}

httplib::Server::HandlerResponse before_routing(RouteState& state, const httplib::Request& request,
                                                httplib::Response& response) {
  request_started = Clock::now();
  refuse_brotli(request);
  const bool versioned = request.path.rfind("/v1/", 0) == 0 || request.path == "/v1";
  if (versioned && !state.options.token.empty()) {
    const std::string header = request.get_header_value("Authorization");
    const std::string prefix = "Bearer ";
    if (header.rfind(prefix, 0) != 0 || !token_matches(header.substr(prefix.size()), state.options.token)) {
      send_problem(response, {ProblemKind::unauthorized, "this server needs 'Authorization: Bearer <token>'", "Authorization"},
                   request.path);
      return httplib::Server::HandlerResponse::Handled;
    }
  }
  // cpp-httplib 0.11.4 reads a POST without Content-Length until the peer closes (curl -X POST
  // sends none): answer a bodiless cancel here, before any read, and refuse other such POSTs.
  if (request.method == "POST" && !request.has_header("Content-Length") && !request.has_header("Transfer-Encoding")) {
    if (const std::string id = cancel_route_id(request.path); !id.empty()) {
      guarded(state.self.lock(), [&state, id](const httplib::Request&, httplib::Response& answer) {
        cancel_job_with_id(state, id, answer);
      })(request, response);
    } else {
      send_problem(response, {ProblemKind::length_required, "send the body with a Content-Length", "Content-Length"},
                   request.path);
      response.set_header("Connection", "close");
    }
    return httplib::Server::HandlerResponse::Handled;
  }
  // cpp-httplib 0.11.4 bounds a body only by its Content-Length, and would inflate gzip or
  // brotli bodies without limit: refuse both kinds before any byte of the body is read.
  if (request.has_header("Transfer-Encoding")) {
    send_problem(response, {ProblemKind::length_required, "send the body with a Content-Length, not chunked", "Transfer-Encoding"},
                 request.path);
    response.set_header("Connection", "close");
    return httplib::Server::HandlerResponse::Handled;
  }
  if (request.has_header("Content-Encoding")) {
    send_problem(response, {ProblemKind::unsupported_media, "compressed request bodies are not accepted", "Content-Encoding"},
                 request.path);
    response.set_header("Connection", "close");
    return httplib::Server::HandlerResponse::Handled;
  }
  return httplib::Server::HandlerResponse::Unhandled;
}

/// Answers for the statuses cpp-httplib produces by itself (unknown route, 413, unreadable
/// request), so they are problem+json like every other error.
httplib::Server::HandlerResponse on_error(const httplib::Request& request, httplib::Response& response) {
  if (!response.body.empty()) return httplib::Server::HandlerResponse::Unhandled;  // ours already
  ProblemKind kind = ProblemKind::internal;
  std::string detail = "internal error";
  switch (response.status) {
    case 404: kind = ProblemKind::not_found; detail = "no route " + request.method + " " + request.path; break;
    case 405: kind = ProblemKind::method_not_allowed; detail = "method " + request.method + " not allowed here"; break;
    case 413: kind = ProblemKind::payload_too_large; detail = "the body is larger than this server accepts (--max-body)"; break;
    case 400: kind = ProblemKind::malformed_body; detail = "the request could not be read"; break;
    default:
      if (response.status < 500) {
        kind = ProblemKind::malformed_body;
        detail = "the request could not be handled";
      }
  }
  const int status = response.status;
  send_problem(response, {kind, detail, kind == ProblemKind::payload_too_large ? "body" : ""}, request.path);
  response.status = status;  // keep what cpp-httplib decided (e.g. 414), with our body
  return httplib::Server::HandlerResponse::Handled;
}

}  // namespace

void register_routes(httplib::Server& server, Service& service, RouteOptions options) {
  auto state = std::make_shared<RouteState>(service, std::move(options));
  state->self = state;
  const std::string id = id_pattern;
  auto route = [&state](void (*handler)(RouteState&, const httplib::Request&, httplib::Response&)) {
    return guarded(state, [state, handler](const httplib::Request& request, httplib::Response& response) {
      handler(*state, request, response);
    });
  };

  server.set_payload_max_length(state->options.max_body);
  server.set_pre_routing_handler(
      [state](const httplib::Request& request, httplib::Response& response) { return before_routing(*state, request, response); });
  server.set_error_handler(httplib::Server::HandlerWithResponse(on_error));
  server.set_exception_handler([state](const httplib::Request& request, httplib::Response& response, std::exception_ptr) {
    // Handlers are guarded; this is the net under the net (and stops 0.11.4 from copying the
    // exception's text into a response header).
    send_problem(response, {ProblemKind::internal, "internal error; see the server log", ""}, request.path);
  });
  server.set_logger([state](const httplib::Request& request, const httplib::Response& response) {
    {
      std::lock_guard lock(state->mutex);
      ++state->requests[request.method + "," + std::to_string(response.status)];
    }
    if (!state->options.log) return;
    char line[96];
    std::snprintf(line, sizeof line, " %d %zu bytes %.1f ms", response.status, response.body.size(),
                  std::chrono::duration<double, std::milli>(Clock::now() - request_started).count());
    state->options.log(request.remote_addr + " " + request.method + " " + request.target + line);
  });

  server.Get("/healthz", guarded(state, [state](const httplib::Request&, httplib::Response& response) {
               const bool up = state->service.accepting();
               send_json(response, up ? 200 : 503, {{"status", up ? "ok" : "shutting down"}});
             }));
  server.Get("/metrics", guarded(state, [state](const httplib::Request&, httplib::Response& response) {
               response.status = 200;
               response.set_content(state->service.metrics() + request_metrics(*state), "text/plain; version=0.0.4");
             }));
  server.Get("/openapi.json", guarded(state, [](const httplib::Request&, httplib::Response& response) {
               response.status = 200;
               response.set_content(openapi_json(), "application/json");
             }));

  // The dashboard: static files, so outside the token's reach (its API calls are not). One
  // page answers every view's address, so /jobs/{id} can be bookmarked and reloaded.
  const auto page = guarded(state, [](const httplib::Request&, httplib::Response& response) { send_asset(response, "/"); });
  server.Get("/", page);
  server.Get("/jobs/" + id, page);
  server.Get("/assets/([A-Za-z0-9._-]{1,64})", guarded(state, [](const httplib::Request& request, httplib::Response& response) {
               send_asset(response, "/assets/" + std::string(request.matches[1]));
             }));

  server.Post("/v1/datasets", route(create_dataset));
  server.Get("/v1/datasets", route(list_datasets));
  server.Get("/v1/datasets/" + id, route(get_dataset));
  server.Get("/v1/datasets/" + id + "/data", route(get_dataset_data));
  server.Delete("/v1/datasets/" + id, route(delete_dataset));

  server.Get("/v1/presets", route(list_presets));
  server.Get("/v1/presets/" + id, route(get_preset));
  server.Post("/v1/simulations", guarded(state, [state](const httplib::Request& request, httplib::Response& response) {
                submit(*state, request, response, JobKind::simulation);
              }));
  server.Post("/v1/identifications", guarded(state, [state](const httplib::Request& request, httplib::Response& response) {
                submit(*state, request, response, JobKind::identification);
              }));

  server.Get("/v1/jobs", route(list_jobs));
  server.Get("/v1/jobs/" + id, route(get_job));
  server.Get("/v1/jobs/" + id + "/history", route(job_history));
  server.Get("/v1/jobs/" + id + "/fit", route(job_fit));
  server.Post("/v1/jobs/" + id + "(?:/cancel|:cancel)", route(cancel_job));
  server.Delete("/v1/jobs/" + id, route(delete_job));
}

}  // namespace manipid::api

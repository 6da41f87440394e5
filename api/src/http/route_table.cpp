// route_table.cpp — register_routes (routes.h): which path goes to which handler, and the
// hooks every request passes through (pre-routing guards, error and exception handlers,
// logger and request counters), installed in one place.
#include "manipid/api/routes.h"

#include "http/httplib_guards.h"  // includes httplib.h, after the manipid headers
#include "http/request_helpers.h"
#include "http/responses.h"
#include "routes/handlers.h"

#include <chrono>
#include <cstdio>
#include <memory>
#include <regex>
#include <string>
#include <utility>

namespace manipid::api {
namespace {

using Clock = std::chrono::steady_clock;

constexpr const char* id_pattern = "([A-Za-z0-9_-]{1,64})";

/// When the request on this thread reached the pre-routing hook; the logger reports the time since.
thread_local Clock::time_point request_started;

/// The table's pen: registers a handler, guarded, for a method and a path pattern, and notes
/// the pair for the Allow header of a 405 (httplib_guards.cpp).
class Table {
 public:
  Table(httplib::Server& server, std::shared_ptr<http::RouteState> state) : server_(server), state_(std::move(state)) {}

  void Get(const std::string& pattern, http::RouteHandler handler) { server_.Get(pattern, note("GET", pattern, handler)); }
  void Post(const std::string& pattern, http::RouteHandler handler) { server_.Post(pattern, note("POST", pattern, handler)); }
  void Delete(const std::string& pattern, http::RouteHandler handler) {
    server_.Delete(pattern, note("DELETE", pattern, handler));
  }

 private:
  httplib::Server::Handler note(const char* method, const std::string& pattern, http::RouteHandler handler) {
    state_->routes.emplace_back(method, std::regex(pattern));
    return http::guarded(state_, [state = state_, handler](const httplib::Request& request, httplib::Response& response) {
      handler(*state, request, response);
    });
  }

  httplib::Server& server_;
  std::shared_ptr<http::RouteState> state_;
};

}  // namespace

void register_routes(httplib::Server& server, Service& service, RouteOptions options) {
  using namespace http;
  auto state = std::make_shared<RouteState>(service, std::move(options));
  state->self = state;
  // The tokens as compared: their digests, never the tokens (request_helpers.h: identify).
  if (!state->options.token.empty()) {
    state->credentials.push_back({Caller{"", true}, sha256_hex({state->options.token})});
  }
  for (const NamedToken& named : state->options.tokens) {
    state->credentials.push_back({Caller{named.name, named.admin}, sha256_hex({named.token})});
  }
  const std::string id = id_pattern;

  // ---- Hooks (http/httplib_guards.h says what each guards against) ----
  server.set_payload_max_length(state->options.max_body);
  server.set_pre_routing_handler([state](const httplib::Request& request, httplib::Response& response) {
    request_started = Clock::now();
    return before_routing(*state, request, response);
  });
  server.set_expect_100_continue_handler([state](const httplib::Request& request, httplib::Response& response) {
    request_started = Clock::now();
    return before_continue(*state, request, response);
  });
  server.set_error_handler(httplib::Server::HandlerWithResponse(
      [state](const httplib::Request& request, httplib::Response& response) { return on_error(*state, request, response); }));
  server.set_exception_handler(on_exception);
  server.set_post_routing_handler([state](const httplib::Request& request, httplib::Response& response) {
    after_routing(*state, request, response);
  });
  server.set_logger([state](const httplib::Request& request, const httplib::Response& response) {
    {
      std::lock_guard lock(state->mutex);
      ++state->requests[method_label(request.method) + "," + std::to_string(response.status)];
    }
    if (!state->options.log) return;
    char line[96];
    std::snprintf(line, sizeof line, " %d %zu bytes %.1f ms", response.status, response.body.size(),
                  std::chrono::duration<double, std::milli>(Clock::now() - request_started).count());
    // Whom a named token stood for (never the token itself): its name ends the line.
    const auto caller = identify(*state, request);
    const std::string owner = caller && !caller->owner.empty() ? " by " + caller->owner : "";
    state->options.log(request.remote_addr + " " + request.method + " " + request.target + line + owner);
  });

  Table routes(server, state);

  // ---- Static files (routes/static_files.cpp): outside the bearer token's reach ----
  routes.Get("/healthz", health);
  routes.Get("/metrics", metrics);
  routes.Get("/openapi.json", openapi_document);
  routes.Get("/", dashboard_page);
  routes.Get("/jobs/" + id, dashboard_page);
  routes.Get("/robots", dashboard_page);
  routes.Get("/robots/" + id, dashboard_page);
  routes.Get("/assets/([A-Za-z0-9._-]{1,64})", dashboard_asset);

  // ---- Datasets (routes/datasets.cpp) ----
  routes.Post("/v1/datasets", create_dataset);
  routes.Get("/v1/datasets", list_datasets);
  routes.Get("/v1/datasets/" + id, get_dataset);
  routes.Get("/v1/datasets/" + id + "/data", get_dataset_data);
  routes.Delete("/v1/datasets/" + id, delete_dataset);

  // ---- Presets and submissions (routes/submissions.cpp) ----
  routes.Get("/v1/presets", list_presets);
  routes.Get("/v1/presets/" + id, get_preset);
  routes.Post("/v1/simulations", submit_simulation);
  routes.Post("/v1/identifications", submit_identification);

  // ---- Jobs (routes/jobs.cpp); a bodiless cancel is answered before routing (httplib_guards.cpp) ----
  routes.Post("/v1/robots", create_robot);
  routes.Get("/v1/robots", list_robots);
  routes.Get("/v1/robots/" + id, get_robot);
  routes.Delete("/v1/robots/" + id, delete_robot);
  routes.Post("/v1/excitations", submit_excitation);

  routes.Get("/v1/jobs", list_jobs);
  routes.Get("/v1/jobs/" + id, get_job);
  routes.Get("/v1/jobs/" + id + "/history", job_history);
  routes.Get("/v1/jobs/" + id + "/fit", job_fit);
  routes.Get("/v1/jobs/" + id + "/validation", job_validation);
  routes.Get("/v1/jobs/" + id + "/urdf", job_urdf);
  routes.Post("/v1/jobs/" + id + "(?:/cancel|:cancel)", cancel_job);
  routes.Delete("/v1/jobs/" + id, delete_job);
}

}  // namespace manipid::api

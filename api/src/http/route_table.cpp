// route_table.cpp — register_routes (routes.h): which path goes to which handler, and the
// hooks every request passes through (pre-routing guards, error and exception handlers,
// logger and request counters), installed in one place.
#include "manipid/api/routes.h"

#include "http/httplib_guards.h"  // includes httplib.h, after the manipid headers
#include "http/responses.h"
#include "routes/handlers.h"

#include <chrono>
#include <cstdio>
#include <memory>

namespace manipid::api {
namespace {

using Clock = std::chrono::steady_clock;

constexpr const char* id_pattern = "([A-Za-z0-9_-]{1,64})";

/// When the request on this thread reached the pre-routing hook; the logger reports the time since.
thread_local Clock::time_point request_started;

}  // namespace

void register_routes(httplib::Server& server, Service& service, RouteOptions options) {
  using namespace http;
  auto state = std::make_shared<RouteState>(service, std::move(options));
  state->self = state;
  const std::string id = id_pattern;
  auto route = [&state](RouteHandler handler) {
    return guarded(state, [state, handler](const httplib::Request& request, httplib::Response& response) {
      handler(*state, request, response);
    });
  };

  // ---- Hooks (http/httplib_guards.h says what each guards against) ----
  server.set_payload_max_length(state->options.max_body);
  server.set_pre_routing_handler([state](const httplib::Request& request, httplib::Response& response) {
    request_started = Clock::now();
    return before_routing(*state, request, response);
  });
  server.set_error_handler(httplib::Server::HandlerWithResponse(on_error));
  server.set_exception_handler(on_exception);
  server.set_logger([state](const httplib::Request& request, const httplib::Response& response) {
    {
      std::lock_guard lock(state->mutex);
      ++state->requests[method_label(request.method) + "," + std::to_string(response.status)];
    }
    if (!state->options.log) return;
    char line[96];
    std::snprintf(line, sizeof line, " %d %zu bytes %.1f ms", response.status, response.body.size(),
                  std::chrono::duration<double, std::milli>(Clock::now() - request_started).count());
    state->options.log(request.remote_addr + " " + request.method + " " + request.target + line);
  });

  // ---- Static files (routes/static_files.cpp): outside the bearer token's reach ----
  server.Get("/healthz", route(health));
  server.Get("/metrics", route(metrics));
  server.Get("/openapi.json", route(openapi_document));
  server.Get("/", route(dashboard_page));
  server.Get("/jobs/" + id, route(dashboard_page));
  server.Get("/assets/([A-Za-z0-9._-]{1,64})", route(dashboard_asset));

  // ---- Datasets (routes/datasets.cpp) ----
  server.Post("/v1/datasets", route(create_dataset));
  server.Get("/v1/datasets", route(list_datasets));
  server.Get("/v1/datasets/" + id, route(get_dataset));
  server.Get("/v1/datasets/" + id + "/data", route(get_dataset_data));
  server.Delete("/v1/datasets/" + id, route(delete_dataset));

  // ---- Presets and submissions (routes/submissions.cpp) ----
  server.Get("/v1/presets", route(list_presets));
  server.Get("/v1/presets/" + id, route(get_preset));
  server.Post("/v1/simulations", route(submit_simulation));
  server.Post("/v1/identifications", route(submit_identification));

  // ---- Jobs (routes/jobs.cpp); a bodiless cancel is answered before routing (httplib_guards.cpp) ----
  server.Get("/v1/jobs", route(list_jobs));
  server.Get("/v1/jobs/" + id, route(get_job));
  server.Get("/v1/jobs/" + id + "/history", route(job_history));
  server.Get("/v1/jobs/" + id + "/fit", route(job_fit));
  server.Post("/v1/jobs/" + id + "(?:/cancel|:cancel)", route(cancel_job));
  server.Delete("/v1/jobs/" + id, route(delete_job));
}

}  // namespace manipid::api

// static_files.cpp — what is not the API's resources: the dashboard's files (embedded in the
// binary), /openapi.json, /healthz and /metrics.
#include "manipid/api/dashboard.h"
#include "manipid/api/problem.h"
#include "manipid/api/routes.h"

#include "http/request_helpers.h"  // includes httplib.h, after the manipid headers
#include "http/responses.h"
#include "routes/handlers.h"

#include <algorithm>
#include <sstream>

namespace manipid::api::http {
namespace {

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

/// The request counters the logger keeps (route_table.cpp) and the memory budget, as Prometheus text.
std::string request_metrics(RouteState& state) {
  std::ostringstream out;
  out << "# HELP manipid_memory_reserved_bytes Memory reserved by the request bodies being read and handled now.\n"
         "# TYPE manipid_memory_reserved_bytes gauge\n"
         "manipid_memory_reserved_bytes "
      << state.memory.reserved() << "\n"
      << "# HELP manipid_memory_budget_bytes What they may reserve at once (--memory-budget).\n"
         "# TYPE manipid_memory_budget_bytes gauge\n"
         "manipid_memory_budget_bytes "
      << state.memory.budget() << "\n";
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

}  // namespace

// The dashboard: static files, so outside the token's reach (its API calls are not). One
// page answers every view's address, so /jobs/{id} can be bookmarked and reloaded.
void dashboard_page(RouteState&, const httplib::Request&, httplib::Response& response) { send_asset(response, "/"); }

void dashboard_asset(RouteState&, const httplib::Request& request, httplib::Response& response) {
  send_asset(response, "/assets/" + std::string(request.matches[1]));
}

void openapi_document(RouteState&, const httplib::Request&, httplib::Response& response) {
  response.status = 200;
  response.set_content(openapi_json(), "application/json");
}

void health(RouteState& state, const httplib::Request&, httplib::Response& response) {
  if (!state.service.accepting()) return send_json(response, 503, {{"status", "shutting down"}});
  // Degraded is still 200: reads and job status answer; only writes are refused (507).
  if (const auto reason = state.service.degraded()) {
    return send_json(response, 200, {{"status", "degraded"}, {"detail", *reason}});
  }
  send_json(response, 200, {{"status", "ok"}});
}

void metrics(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  // Every owner's job counts and every route's request rates: a named token's owner would learn
  // of the others' work, so only an admin token reads them (--token and no token at all are admins).
  if (!caller_of(state, request).admin) {
    throw ApiError(ProblemKind::forbidden, "/metrics counts every owner's jobs: it needs an admin token", "Authorization");
  }
  response.status = 200;
  response.set_content(state.service.metrics() + request_metrics(state), "text/plain; version=0.0.4");
}

}  // namespace manipid::api::http

// handlers.h — internal to the routes: every handler the route table (http/route_table.cpp)
// maps a path to, one section per resource file. A handler maps the request to Service calls,
// made for the request's caller (request_helpers.h: caller_of), and the answer back; it throws
// ApiError or InputError for anything a client can fix, and `guarded` (http/responses.h) turns
// what it throws into problem+json.
//
// A new resource (robots, say) is a routes/robots.cpp with its handlers, a section here, and
// its lines in the route table.
#pragma once

#include "manipid/api/records.h"
#include "manipid/api/requests.h"
#include "manipid/api/robot_requests.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <optional>

#include "http/route_state.h"  // includes httplib.h, after the manipid headers

#include <string>

namespace manipid::api::http {

// ---- datasets.cpp: /v1/datasets ----------------------------------------------------------

void create_dataset(RouteState& state, const httplib::Request& request, httplib::Response& response);
void list_datasets(RouteState& state, const httplib::Request& request, httplib::Response& response);
void get_dataset(RouteState& state, const httplib::Request& request, httplib::Response& response);
void get_dataset_data(RouteState& state, const httplib::Request& request, httplib::Response& response);
void delete_dataset(RouteState& state, const httplib::Request& request, httplib::Response& response);

// ---- submissions.cpp: /v1/presets, /v1/simulations, /v1/identifications -------------------

void list_presets(RouteState& state, const httplib::Request& request, httplib::Response& response);
void get_preset(RouteState& state, const httplib::Request& request, httplib::Response& response);
void submit_simulation(RouteState& state, const httplib::Request& request, httplib::Response& response);
void submit_identification(RouteState& state, const httplib::Request& request, httplib::Response& response);
/// A submission of the kind `kind_of` says the body asks for: checked by that kind's entry of job_kinds.h against
/// the caller's datasets and robots, then queued; 202 with the job (Location, Idempotent-Replayed on a replay).
void submit_job(RouteState& state, const httplib::Request& request, httplib::Response& response,
                const std::function<JobKind(const nlohmann::json& body)>& kind_of);

// ---- robots.cpp: /v1/robots, /v1/excitations ------------------------------------------------

void create_robot(RouteState& state, const httplib::Request& request, httplib::Response& response);
void list_robots(RouteState& state, const httplib::Request& request, httplib::Response& response);
void get_robot(RouteState& state, const httplib::Request& request, httplib::Response& response);
void delete_robot(RouteState& state, const httplib::Request& request, httplib::Response& response);
void submit_excitation(RouteState& state, const httplib::Request& request, httplib::Response& response);
/// A stored robot the caller sees, parsed again (as a job does), for requests checked against it;
/// InputError-like ApiError (422, `field`) when there is no such robot (or it is another owner's).
std::shared_ptr<const ParsedRobot> stored_robot(RouteState& state, const Caller& caller, const std::string& id,
                                                const std::string& field);

// ---- jobs.cpp: /v1/jobs ------------------------------------------------------------------

void list_jobs(RouteState& state, const httplib::Request& request, httplib::Response& response);
void get_job(RouteState& state, const httplib::Request& request, httplib::Response& response);
void job_history(RouteState& state, const httplib::Request& request, httplib::Response& response);
void job_fit(RouteState& state, const httplib::Request& request, httplib::Response& response);
void job_validation(RouteState& state, const httplib::Request& request, httplib::Response& response);
void job_urdf(RouteState& state, const httplib::Request& request, httplib::Response& response);
void cancel_job(RouteState& state, const httplib::Request& request, httplib::Response& response);
void delete_job(RouteState& state, const httplib::Request& request, httplib::Response& response);

/// The job as JSON with `status`, and Retry-After: 1 while it is not terminal (submissions
/// answer with it too).
void send_job(httplib::Response& response, int status, const JobInfo& job);
/// The cancel of job `id` for `caller`; also called from the pre-routing guard for a bodiless cancel.
void cancel_job_with_id(RouteState& state, const Caller& caller, const std::string& id, httplib::Response& response);
/// The job id of "/v1/jobs/{id}/cancel" or "/v1/jobs/{id}:cancel", else empty.
std::string cancel_route_id(const std::string& path);

// ---- static_files.cpp: the dashboard, /openapi.json, /healthz, /metrics -------------------

void dashboard_page(RouteState& state, const httplib::Request& request, httplib::Response& response);
void dashboard_asset(RouteState& state, const httplib::Request& request, httplib::Response& response);
void openapi_document(RouteState& state, const httplib::Request& request, httplib::Response& response);
void health(RouteState& state, const httplib::Request& request, httplib::Response& response);
void metrics(RouteState& state, const httplib::Request& request, httplib::Response& response);

}  // namespace manipid::api::http

// responses.h — internal to the routes: writing answers (JSON, problem+json) and `guarded`,
// which turns everything a handler throws into problem+json, so a bad request can never take
// the server down or leave half a change behind.
#pragma once

#include "manipid/api/problem.h"

#include "http/route_state.h"  // includes httplib.h, after the manipid headers

#include "manipid/api/http_server.h"

#include <nlohmann/json.hpp>

#include <exception>
#include <memory>
#include <new>
#include <string>

namespace manipid::api::http {

void send_json(httplib::Response& response, int status, const nlohmann::ordered_json& body);

/// The problem as application/problem+json with its status; Retry-After for queue_full,
/// shutting_down, memory_busy, store_unavailable and uploads_busy, WWW-Authenticate for unauthorized.
void send_problem(httplib::Response& response, const Problem& problem, const std::string& instance);

/// What a request that ran out of memory is answered (memory_busy: it may succeed later).
Problem out_of_memory();

/// Runs a handler; every failure becomes a problem+json answer (internal details only in the log).
template <class Handler>
httplib::Server::Handler guarded(std::shared_ptr<RouteState> state, Handler handler) {
  return [state, handler](const httplib::Request& request, httplib::Response& response) {
    HttpServer::body_received();  // httplib has read the body: its deadline is met
    try {
      handler(request, response);
    } catch (const ApiError& error) {
      send_problem(response, error.problem(), request.path);
    } catch (const InputError& error) {
      send_problem(response, problem_from(error), request.path);
    } catch (const std::bad_alloc&) {
      send_problem(response, out_of_memory(), request.path);
    } catch (const std::exception& error) {
      if (state->options.log) state->options.log(std::string("internal error on ") + request.path + ": " + error.what());
      send_problem(response, {ProblemKind::internal, "internal error; see the server log", ""}, request.path);
    }
  };
}

}  // namespace manipid::api::http

// responses.cpp — writing answers: JSON bodies and problem+json errors (responses.h).
#include "manipid/api/problem.h"

#include "http/responses.h"  // includes httplib.h, after the manipid headers

namespace manipid::api::http {

void send_json(httplib::Response& response, int status, const nlohmann::ordered_json& body) {
  response.status = status;
  // A stored row from before names were checked could hold invalid UTF-8: answered with U+FFFD, never a 500.
  response.set_content(body.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace), "application/json");
}

Problem out_of_memory() {
  return {ProblemKind::memory_busy, "the server ran out of memory while handling this request; try again later", ""};
}

void send_problem(httplib::Response& response, const Problem& problem, const std::string& instance) {
  response.status = status_of(problem.kind);
  response.set_content(problem_to_json(problem, instance).dump(), "application/problem+json");
  if (problem.kind == ProblemKind::queue_full || problem.kind == ProblemKind::shutting_down ||
      problem.kind == ProblemKind::insufficient_storage || problem.kind == ProblemKind::memory_busy ||
      problem.kind == ProblemKind::store_unavailable || problem.kind == ProblemKind::uploads_busy) {
    response.set_header("Retry-After", "5");
  }
  if (problem.kind == ProblemKind::unauthorized) response.set_header("WWW-Authenticate", "Bearer");
}

}  // namespace manipid::api::http

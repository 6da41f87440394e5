// httplib_guards.h — internal to the routes: the hooks that stand between Debian's
// cpp-httplib 0.11.4 and the handlers. Each exists for a 0.11.4 behaviour, named beside it in
// httplib_guards.cpp: bodies read without bound (or, refused, read as the next request: with
// HttpServer, every refusal closes its connection), Brotli at quality 11, its own error statuses
// with empty bodies (and 404 for a wrong method), invented methods passed to the logger,
// exception text copied into a response header. The route table (route_table.cpp) installs them.
#pragma once

#include "http/route_state.h"  // includes httplib.h, after the manipid headers

#include <exception>
#include <string>

namespace manipid::api::http {

/// Strikes "br" from the request's Accept-Encoding (gzip stays): 0.11.4's Brotli is quality 11.
void refuse_brotli(const httplib::Request& request);

/// The pre-routing hook: runs before any byte of the body is read. Body framing (two
/// Content-Lengths, Content-Length beside Transfer-Encoding, a body on a GET: 400) and a
/// declared length over --max-body (413), Brotli strike, bearer token on /v1 and /metrics (401
/// unless it is one the server takes: request_helpers.h's identify), bodiless POST,
/// PUT or PATCH (411, but a bodiless cancel is answered), chunked (411) and compressed (415)
/// bodies refused; then one of the places for bodies being received at once taken
/// (HttpServer::admit_body: 503 UPLOADS_BUSY beyond them) and the body's memory reserved
/// (RouteOptions::memory_budget; 503 when there is no room). Every refusal closes the
/// connection (HttpServer::close_after_answer).
httplib::Server::HandlerResponse before_routing(RouteState& state, const httplib::Request& request,
                                                httplib::Response& response);

/// The "Expect: 100-continue" hook: 0.11.4 answers "100 Continue" before the pre-routing hook
/// runs, so a body that will be refused (bad framing, over --max-body, no upload place or no
/// room in the memory budget) is refused here, before the client sends it (curl asks so for
/// bodies over 1 MiB).
/// Returns 100 or the refusal's status.
int before_continue(RouteState& state, const httplib::Request& request, httplib::Response& response);

/// The post-routing hook (0.11.4 runs it after adding its own Connection or Keep-Alive
/// header): gives back the request's memory reservation; an answer that closes its connection
/// says "Connection: close" once, and no "Keep-Alive" beside it.
void after_routing(RouteState& state, const httplib::Request& request, httplib::Response& response);

/// The request's method as a /metrics label: one of the methods httplib parses, else "other".
std::string method_label(const std::string& method);

/// The error hook: problem+json for the statuses cpp-httplib produces by itself (unknown
/// route, 413, unreadable request), and 405 with Allow where it says 404 for a known path.
httplib::Server::HandlerResponse on_error(const RouteState& state, const httplib::Request& request,
                                          httplib::Response& response);

/// The exception hook: the net under `guarded`'s net; 500 problem+json, nothing of the
/// exception in the answer.
void on_exception(const httplib::Request& request, httplib::Response& response, std::exception_ptr error);

}  // namespace manipid::api::http

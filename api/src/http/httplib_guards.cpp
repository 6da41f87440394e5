// httplib_guards.cpp — the cpp-httplib 0.11.4 guards (httplib_guards.h): each hook below says
// which behaviour of Debian's 0.11.4 it exists for.
#include "manipid/api/problem.h"

#include "http/httplib_guards.h"  // includes httplib.h, after the manipid headers
#include "http/request_helpers.h"
#include "http/responses.h"
#include "routes/handlers.h"

#include "manipid/api/http_server.h"  // includes httplib.h

#include <algorithm>
#include <cctype>
#include <iterator>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

namespace manipid::api::http {

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

namespace {

/// A refusal before the body is read: the answer, then the connection is closed, so the
/// unread body can never be read as the next request (HttpServer::close_after_answer).
httplib::Server::HandlerResponse refuse(httplib::Response& response, const Problem& problem, const std::string& instance) {
  send_problem(response, problem, instance);
  HttpServer::close_after_answer(response);
  return httplib::Server::HandlerResponse::Handled;
}

/// The body's framing, checked before anything else: RFC 9112 § 6.3 makes a request with
/// two Content-Lengths, or Content-Length beside Transfer-Encoding, a smuggling attempt
/// (0.11.4 takes the first Content-Length and ignores the rest); a body on a GET is the same
/// hole (0.11.4 never reads it). Empty when the framing is fine.
std::optional<Problem> framing_problem(const httplib::Request& request) {
  const std::size_t lengths = request.get_header_value_count("Content-Length");
  if (lengths > 1) {
    return Problem{ProblemKind::malformed_body, "send one Content-Length header, not " + std::to_string(lengths),
                   "Content-Length"};
  }
  if (lengths == 1 && request.has_header("Transfer-Encoding")) {
    return Problem{ProblemKind::malformed_body, "send either Content-Length or Transfer-Encoding, not both",
                   "Transfer-Encoding"};
  }
  if (lengths == 1) {
    const std::string value = request.get_header_value("Content-Length");
    if (value.empty() || !std::all_of(value.begin(), value.end(), [](unsigned char c) { return std::isdigit(c) != 0; })) {
      return Problem{ProblemKind::malformed_body, "Content-Length must be a number of bytes", "Content-Length"};
    }
  }
  // 0.11.4 never reads the body of a GET, HEAD or OPTIONS: it would be read as the next
  // request. It reads a DELETE's, but no route takes one: refused alike, so only the methods
  // that carry bodies here (POST; PUT, PATCH and PRI reach their 405) may have one.
  const bool body_read = request.method == "POST" || request.method == "PUT" || request.method == "PATCH" ||
                         request.method == "PRI";
  const bool has_body = request.has_header("Transfer-Encoding") ||
                        (lengths == 1 && request.get_header_value("Content-Length").find_first_not_of('0') != std::string::npos);
  if (!body_read && has_body) {
    return Problem{ProblemKind::malformed_body, request.method + " requests take no body", "body"};
  }
  return std::nullopt;
}

/// The declared Content-Length (digits only, checked by framing_problem, of any length: it is
/// compared as a digit string, never converted) is above `limit`.
bool declared_above(const std::string& value, std::size_t limit) {
  const std::string digits = value.substr(std::min(value.find_first_not_of('0'), value.size()));
  const std::string bound = std::to_string(limit);
  if (digits.size() != bound.size()) return digits.size() > bound.size();
  return digits > bound;
}

/// What is wrong with the request's framing or declared size, before anything else is looked at.
std::optional<Problem> length_problem(const RouteState& state, const httplib::Request& request) {
  if (auto problem = framing_problem(request)) return problem;
  // 0.11.4 checks --max-body only after reading (and dropping) the whole declared body, 10 GB
  // in 9.5 s: answer from the header instead, and close, never reading a byte of it.
  if (request.has_header("Content-Length") && declared_above(request.get_header_value("Content-Length"), state.options.max_body)) {
    return Problem{ProblemKind::payload_too_large,
                   "the body is larger than this server accepts (--max-body " + std::to_string(state.options.max_body) + " bytes)",
                   "body"};
  }
  return std::nullopt;
}

/// Admits the request's body against the memory budget (its reservation, given back by
/// after_routing); the refusal when there is no room for it now.
std::optional<Problem> memory_problem(RouteState& state, const httplib::Request& request) {
  // The body is read whole into memory, then parsed and stored: 8 uploads of 60 MB at once took
  // 8.7 GB. Each is admitted before a byte of it is read; beyond the budget, 503 with
  // Retry-After, and the connection closes with the body unread.
  const std::size_t declared = request.has_header("Content-Length") ? std::stoull(request.get_header_value("Content-Length")) : 0;
  if (declared == 0 || state.memory.reserve(declared * memory_per_body_byte)) return std::nullopt;
  return Problem{ProblemKind::memory_busy,
                 "the server is reading other large bodies (--memory-budget " + std::to_string(state.memory.budget()) +
                     " bytes, " + std::to_string(memory_per_body_byte) + " per body byte); try again later",
                 "body"};
}

/// Takes one of the places for bodies being received at once (HttpServer::admit_body) for a
/// request with a body; the refusal when every place is taken. A body trickled a byte a second
/// holds the thread reading it until its deadline (10 s + length / 256 KiB/s: 48 s for 10 MB),
/// so those threads do not count toward --http-threads; their number is bounded here instead,
/// per client address first, so that one client cannot take every place.
std::optional<Problem> upload_problem(const httplib::Request& request) {
  if (!request.has_header("Content-Length") ||
      request.get_header_value("Content-Length").find_first_not_of('0') == std::string::npos) {
    return std::nullopt;
  }
  const auto refusal = HttpServer::admit_body();
  if (!refusal) return std::nullopt;
  const std::string limit = std::to_string(refusal->limit);
  return Problem{ProblemKind::uploads_busy,
                 refusal->per_client
                     ? "this address is sending " + limit + " request bodies at once already (--max-uploads-per-client " + limit + "); try again later"
                     : "the server is receiving " + limit + " request bodies at once already (--max-uploads " + limit + "); try again later",
                 "body"};
}

}  // namespace

int before_continue(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  HttpServer::head_received();
  auto problem = length_problem(state, request);
  if (!problem) problem = upload_problem(request);
  if (!problem) problem = memory_problem(state, request);
  if (problem) {
    refuse(response, *problem, request.path);
    // This answer goes out through 0.11.4's plain write_response, which adds no Content-Length.
    response.set_header("Content-Length", std::to_string(response.body.size()));
    return response.status;
  }
  return 100;
}

httplib::Server::HandlerResponse before_routing(RouteState& state, const httplib::Request& request,
                                                httplib::Response& response) {
  HttpServer::head_received();
  refuse_brotli(request);
  if (const auto problem = length_problem(state, request)) return refuse(response, *problem, request.path);
  // The body (digits, at most --max-body: checked above) gets its own deadline.
  HttpServer::head_received(request.has_header("Content-Length")
                                ? std::stoull(request.get_header_value("Content-Length"))
                                : 0);
  // The bearer token guards the API and /metrics (job counts, memory, request rates are the lab's
  // business; Prometheus sends a bearer token with `authorization`): the dashboard's static files and
  // /healthz stay outside its reach (the page asks for the token and sends it with its own API calls).
  // Which token it is — whose resources the request sees — the handlers ask again (caller_of).
  const bool needs_token = request.path.rfind("/v1/", 0) == 0 || request.path == "/v1" || request.path == "/metrics";
  if (needs_token && !identify(state, request)) {
    return refuse(response,
                  {ProblemKind::unauthorized, "this server needs 'Authorization: Bearer <token>'", "Authorization"},
                  request.path);
  }
  // cpp-httplib 0.11.4 reads a POST without Content-Length until the peer closes (curl -X POST
  // sends none): answer a bodiless cancel here, before any read, and refuse other such POSTs.
  // It reads PUT, PATCH and PRI the same way (its expect_content), though no route takes them:
  // refused too, or each such request holds a server thread and grows a body without bound.
  const bool body_expected = request.method == "POST" || request.method == "PUT" || request.method == "PATCH" ||
                             request.method == "PRI";
  if (body_expected && !request.has_header("Content-Length") && !request.has_header("Transfer-Encoding")) {
    if (const std::string id = request.method == "POST" ? cancel_route_id(request.path) : ""; !id.empty()) {
      guarded(state.self.lock(), [&state, id](const httplib::Request& cancel, httplib::Response& answer) {
        cancel_job_with_id(state, caller_of(state, cancel), id, answer);
      })(request, response);
      return httplib::Server::HandlerResponse::Handled;
    }
    return refuse(response, {ProblemKind::length_required, "send the body with a Content-Length", "Content-Length"},
                  request.path);
  }
  // cpp-httplib 0.11.4 bounds a body only by its Content-Length, and would inflate gzip or
  // brotli bodies without limit: refuse both kinds before any byte of the body is read.
  if (request.has_header("Transfer-Encoding")) {
    return refuse(response,
                  {ProblemKind::length_required, "send the body with a Content-Length, not chunked", "Transfer-Encoding"},
                  request.path);
  }
  if (request.has_header("Content-Encoding")) {
    return refuse(response,
                  {ProblemKind::unsupported_media, "compressed request bodies are not accepted", "Content-Encoding"},
                  request.path);
  }
  if (const auto problem = upload_problem(request)) return refuse(response, *problem, request.path);
  if (const auto problem = memory_problem(state, request)) return refuse(response, *problem, request.path);
  return httplib::Server::HandlerResponse::Unhandled;
}

void after_routing(RouteState& state, const httplib::Request&, httplib::Response& response) {
  state.memory.release();  // the answer is made: the request's body is no longer needed

  if (response.get_header_value("Connection") != "close") return;
  response.headers.erase("Connection");
  response.headers.erase("Keep-Alive");
  response.set_header("Connection", "close");
}

/// cpp-httplib 0.11.4 calls the logger for a request it refused at the request line (400),
/// with the method as sent: any token, quotes and braces included. As a label it would break
/// the Prometheus text of /metrics and add a counter per token a client cares to invent.
std::string method_label(const std::string& method) {
  static const char* const known[] = {"GET", "HEAD", "POST", "PUT", "DELETE", "OPTIONS", "PATCH", "CONNECT", "TRACE", "PRI"};
  const bool listed = std::any_of(std::begin(known), std::end(known), [&method](const char* name) { return method == name; });
  return listed ? method : "other";
}

namespace {

/// The methods the routes take on `path` ("DELETE, GET, HEAD"; HEAD wherever GET is, as httplib
/// answers it), or empty when no route matches the path at all.
std::string allowed_methods(const RouteState& state, const std::string& path) {
  std::set<std::string> methods;
  for (const auto& [method, pattern] : state.routes) {
    if (std::regex_match(path, pattern)) methods.insert(method);  // as httplib matches a route
  }
  if (methods.count("GET")) methods.insert("HEAD");
  std::string allow;
  for (const std::string& method : methods) allow += (allow.empty() ? "" : ", ") + method;
  return allow;
}

/// Why httplib could not read `head`, in words: a header line longer than it reads names its header
/// (a 10,000-character Idempotency-Key was only "the request could not be read").
std::string unreadable_head(std::string_view head) {
  constexpr std::size_t line_limit = 8192;  // cpp-httplib 0.11.4's CPPHTTPLIB_HEADER_MAX_LENGTH
  std::size_t begin = head.find('\n');  // past the request line (its own limit answers 414)
  while (begin != std::string_view::npos && begin + 1 < head.size()) {
    ++begin;
    const std::size_t end = head.find('\n', begin);
    const std::string_view line = head.substr(begin, end == std::string_view::npos ? std::string_view::npos : end + 1 - begin);
    if (line == "\r\n" || line == "\n") break;  // the end of the head
    if (line.size() >= line_limit) {
      std::string name(line.substr(0, std::min(line.find(':'), std::size_t{40})));
      for (char& c : name) {
        if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
      }
      return "the header " + name + " is " + std::to_string(line.size()) + " bytes long; this server reads header lines of at "
             "most " + std::to_string(line_limit) + " bytes" +
             (name == "Idempotency-Key" || name == "idempotency-key" ? " (an Idempotency-Key is 1 to 255 characters)" : "");
    }
    begin = end;
  }
  return "the request could not be read";
}

}  // namespace

/// Answers for the statuses cpp-httplib produces by itself (unknown route, 413, unreadable
/// request), so they are problem+json like every other error: 0.11.4 sends them with an
/// empty body (413 comes from set_payload_max_length, checked against Content-Length only).
/// 0.11.4 also says 404 for a path whose routes take other methods only: that is a 405 with
/// the methods they take in Allow (RFC 9110 § 15.5.6).
httplib::Server::HandlerResponse on_error(const RouteState& state, const httplib::Request& request,
                                          httplib::Response& response) {
  HttpServer::body_received();
  // 0.11.4 applies the request's Range to every answer it writes, errors included (a 401 cut to
  // its first 11 bytes, with Content-Range; found by tests/fuzz/http_fuzz): only a successful
  // answer may be partial (RFC 9110 § 14.2). It calls this hook for every status from 400 up
  // before it applies them, so an error drops them here (the Request is httplib's own, non-const).
  const_cast<httplib::Request&>(request).ranges.clear();
  if (!response.body.empty()) return httplib::Server::HandlerResponse::Unhandled;  // ours already
  ProblemKind kind = ProblemKind::internal;
  std::string detail = "internal error";
  switch (response.status) {
    case 404:
      if (const std::string allow = allowed_methods(state, request.path); !allow.empty()) {
        kind = ProblemKind::method_not_allowed;
        detail = "method " + request.method + " not allowed on " + request.path + "; allowed: " + allow;
        response.status = 405;
        response.set_header("Allow", allow);
      } else {
        kind = ProblemKind::not_found;
        detail = "no route " + request.method + " " + request.path;
      }
      break;
    case 405: kind = ProblemKind::method_not_allowed; detail = "method " + request.method + " not allowed here"; break;
    case 413:
      if (request.get_header_value("Content-Type").rfind("application/x-www-form-urlencoded", 0) == 0 &&
          request.get_header_value<uint64_t>("Content-Length") <= state.options.max_body) {
        // cpp-httplib reads a form-urlencoded body only up to 8 KiB: the label curl puts on `--data-binary
        // @file` and `-d @file` unless told otherwise. The body is not too large; its label is wrong.
        kind = ProblemKind::unsupported_media;
        detail = "the body came as application/x-www-form-urlencoded, as curl labels --data-binary and -d unless told "
                 "otherwise, and is read that way only up to 8 KiB: send it with its type, e.g. "
                 "curl --data-binary @run.csv -H 'Content-Type: text/csv' (application/json for JSON, "
                 "application/xml for a URDF, application/vnd.sqlite3 for a ROS 2 bag); use --data-binary, not -d, which "
                 "drops the file's line ends";
        response.status = status_of(kind);
      } else {
        kind = ProblemKind::payload_too_large;
        detail = "the body is larger than this server accepts (--max-body " + std::to_string(state.options.max_body) + " bytes)";
      }
      break;
    case 414: kind = ProblemKind::uri_too_long; detail = "the request target is longer than this server reads"; break;
    case 400:
      kind = ProblemKind::malformed_body;
      detail = unreadable_head(HttpServer::current_head());
      break;
    default:
      // Below 500 that leaves 416, which 0.11.4 sends for a Range header it cannot parse, before
      // reading the body: a 400 (the problem's own status, so the status line and the body agree;
      // found by tests/fuzz/http_fuzz), and the connection closes below, the body unread.
      if (response.status < 500) {
        kind = ProblemKind::malformed_body;
        detail = response.status == 416 ? "the Range header could not be read" : "the request could not be handled";
        response.status = status_of(kind);
      }
  }
  const int status = response.status;
  send_problem(response, {kind, detail, kind == ProblemKind::payload_too_large ? "body" : ""}, request.path);
  response.status = status;  // keep what cpp-httplib decided, with our body
  // A request httplib could not read (400, 414) or refused by its length (413) may have left
  // bytes on the connection that are not the start of a request: close it after the answer.
  if (status == 400 || status == 413 || status == 414 || kind == ProblemKind::unsupported_media) {
    HttpServer::close_after_answer(response);
  }
  return httplib::Server::HandlerResponse::Handled;
}

void on_exception(const httplib::Request& request, httplib::Response& response, std::exception_ptr error) {
  // Handlers are guarded; this is the net under the net (and stops 0.11.4 from copying the
  // exception's text into a response header, EXCEPTION_WHAT). Reading a body into memory can
  // run out of it here, outside any handler: that is worth trying again. The body is then half
  // read, and what is left of it is not a request: the connection closes after the answer.
  try {
    if (error) std::rethrow_exception(error);
  } catch (const std::bad_alloc&) {
    send_problem(response, out_of_memory(), request.path);
    HttpServer::close_after_answer(response);
    return;
  } catch (...) {
  }
  send_problem(response, {ProblemKind::internal, "internal error; see the server log", ""}, request.path);
}

}  // namespace manipid::api::http

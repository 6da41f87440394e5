// http_endpoint.h — the HTTP side of `manipid serve` behind a seam: cpp-httplib and the routes are
// built into a module, manipid-http.so, that the executable loads when a server starts.
//
// Why a module: Debian's cpp-httplib is a shared library that brings OpenSSL, zlib and Brotli
// with it; loading them cost every process ~2.6 ms before main (an empty program with and without
// -lcpp-httplib, 5.8 against 3.2 ms), a tenth of a whole `manipid identify`, paid by every
// one-shot command that never serves. Loaded with dlopen by `serve` only — as libpq and FFTW are
// loaded by what uses them — the other commands do not pay. The module resolves the rest of
// manipid (api/, core/) against the executable, which exports its symbols for it, so there is one
// copy of every function and every static in the process.
#pragma once

#include "manipid/api/routes.h"
#include "manipid/api/service.h"

#include <cstddef>
#include <memory>
#include <string>

namespace manipid::api {

/// How `manipid serve` serves connections. The rest of its connection policy (keep-alive,
/// timeouts, the header deadline, the backlog) is fixed in the module and argued there
/// (api/src/http/http_endpoint.cpp).
struct HttpSettings {
  std::size_t threads = 32;  ///< requests served at once (besides the bodies being received)
  /// Connections waiting for a request head (new, or idle between requests), from one client
  /// address and in all; beyond, the oldest waiting one is closed (HttpServer::set_connection_limits).
  std::size_t max_connections_per_client = 64;
  std::size_t max_connections = 4096;
  /// Request bodies being received at once, from one client address and in all; beyond, 503
  /// UPLOADS_BUSY before the body is read (HttpServer::set_upload_limits).
  std::size_t max_uploads_per_client = 16;
  std::size_t max_uploads = 256;
  RouteOptions routes;
};

/// An HTTP server over a Service with every route registered: bind, then listen until stopped.
class HttpEndpoint {
 public:
  virtual ~HttpEndpoint() = default;
  /// Binds to `host`:`port` (0: any free port) and listens; the port, or −1.
  virtual int bind(const std::string& host, int port) = 0;
  /// Serves until stopped; false when listening failed. std::system_error when its threads
  /// cannot all be started.
  virtual bool listen_after_bind() = 0;
  virtual bool is_running() const = 0;
  /// Stops listening and shuts every open connection down, so listen_after_bind returns.
  virtual void stop_and_disconnect() = 0;
};

/// The module's file name.
inline constexpr const char* http_module_name = "manipid-http.so";

/// Raised by each change of the module's entry point or of the types it takes: the executable
/// refuses, when it loads it, a module built with another.
inline constexpr int http_module_interface = 3;  // 2: the reactor's settings; 3: Service calls take the Caller (named tokens)

/// Loads the module, once per process: looked for beside the executable, then in ../lib/manipid/
/// from it. std::runtime_error saying where it looked and why each place failed. A server calls
/// it first, so a missing module stops it before it opens anything.
void load_http_module();

/// Makes an endpoint over `service`, which must outlive it (loading the module if need be).
std::unique_ptr<HttpEndpoint> open_http_endpoint(Service& service, const HttpSettings& settings);

}  // namespace manipid::api

// http_endpoint.cpp — the module's entry point (http_endpoint.h): an HttpServer configured as
// `manipid serve` serves, with every route registered over the executable's Service.
#include "manipid/api/http_endpoint.h"

#include "manipid/api/routes.h"

#include "manipid/api/http_server.h"  // includes httplib.h: after the manipid headers (http/route_state.h)

#include <chrono>
#include <memory>
#include <string>

namespace manipid::api {
namespace {

class ServedEndpoint final : public HttpEndpoint {
 public:
  ServedEndpoint(Service& service, const HttpSettings& settings) {
    server_.set_http_threads(settings.threads);
    server_.set_connection_limits(settings.max_connections_per_client, settings.max_connections);
    server_.set_upload_limits(settings.max_uploads_per_client, settings.max_uploads);
    server_.set_log(settings.routes.log);
    // Without TCP_NODELAY, Nagle plus delayed ACKs hold each keep-alive answer (headers and
    // body are two writes) for ~40 ms: 360 status requests/s instead of thousands.
    server_.set_tcp_nodelay(true);
    server_.set_keep_alive_max_count(1000);
    server_.set_keep_alive_timeout(2);
    server_.set_read_timeout(30);
    server_.set_write_timeout(30);
    // A request's line and headers must arrive within 10 s of their first byte, or the
    // connection is closed (per-read timeouts never fire for a byte a second); a connection
    // that sends nothing is closed after the keep-alive timeout. Neither holds a thread meanwhile.
    server_.set_header_deadline(std::chrono::seconds(10));
    server_.set_listen_backlog(128);  // 0.11.4 listens with 5
    register_routes(server_, service, settings.routes);
  }

  int bind(const std::string& host, int port) override { return server_.bind(host, port); }
  bool listen_after_bind() override { return server_.listen_after_bind(); }
  bool is_running() const override { return server_.is_running(); }
  void stop_and_disconnect() override { server_.stop_and_disconnect(); }

 private:
  HttpServer server_;
};

}  // namespace
}  // namespace manipid::api

/// What the executable checks first (http_endpoint_loader.cpp): a module built with another
/// interface is refused when it is loaded.
extern "C" __attribute__((visibility("default"))) const int manipid_http_module_interface = manipid::api::http_module_interface;

/// What the executable calls to make the server. Exceptions stay on this side: a failure to make
/// it is reported in `failure`, with null.
extern "C" __attribute__((visibility("default"))) manipid::api::HttpEndpoint* manipid_open_http_endpoint(
    manipid::api::Service* service, const manipid::api::HttpSettings* settings, std::string* failure) {
  try {
    return new manipid::api::ServedEndpoint(*service, *settings);
  } catch (const std::exception& error) {
    *failure = error.what();
    return nullptr;
  }
}

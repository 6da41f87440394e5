// route_state.h — internal to the routes: what every handler shares (the Service, the
// options, the tokens it takes, the request counters for /metrics) and the handler signature the route table maps
// paths to.
//
// Everything behind register_routes lives in manipid::api::http: the public namespace
// manipid::api stays exactly what include/manipid/api declares (codecs, Service,
// register_routes), and an internal name such as http::create_dataset can neither collide with
// nor be mistaken for a public one (Service::create_dataset, api::dataset_to_json).
//
// Include order, here and in every routes file: the manipid headers come before httplib.h on
// purpose. Debian's httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen if Eigen
// comes second; service.h brings in the core (and Eigen) first.
#pragma once

#include "manipid/api/routes.h"
#include "manipid/api/service.h"

#include "http/memory_budget.h"

#include <httplib.h>

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <regex>
#include <string>
#include <utility>
#include <vector>

namespace manipid::api::http {

/// A token the server takes, as it is compared: the SHA-256 of the token (hex), never the token
/// itself, so each comparison takes the same time whatever the tokens' lengths and contents.
struct Credential {
  Caller caller;
  std::string digest;
};

/// Shared by every handler; lives as long as the server's handlers (captured by shared_ptr).
struct RouteState {
  RouteState(Service& service_, RouteOptions options_)
      : service(service_), options(std::move(options_)), memory(options.memory_budget) {}
  Service& service;
  RouteOptions options;
  MemoryBudget memory;  ///< the bodies being read and handled now (RouteOptions::memory_budget)
  std::weak_ptr<RouteState> self;  ///< for handlers called from the pre-routing hook
  /// RouteOptions::token and RouteOptions::tokens as compared (register_routes fills it); empty:
  /// no token is asked for and every request acts as the admin, owner "".
  std::vector<Credential> credentials;
  std::mutex mutex;
  std::map<std::string, long> requests;  ///< "METHOD,status" → count
  std::atomic<int> waiters{0};           ///< ?wait= long-polls waiting now (RouteOptions::max_waiters)
  /// (method, path pattern) of every route, noted by the route table: the Allow header of a 405.
  std::vector<std::pair<std::string, std::regex>> routes;
};

/// What the route table maps a path to (routes/handlers.h declares them all).
using RouteHandler = void (*)(RouteState&, const httplib::Request&, httplib::Response&);

}  // namespace manipid::api::http

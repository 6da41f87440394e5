// serve.h — `manipid serve`: the HTTP service (store, worker pool, routes).
#pragma once

#include "cli/common.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace manipid::server::cli {

struct ServeOptions {
  std::string host = "127.0.0.1";
  int port = 8080;
  std::string database = "./manipid.db";
  int workers = 0;            ///< 0 = hardware threads
  int queue_limit = 10000;
  std::string max_body = "64MiB";
  std::string memory_budget = "1GiB";  ///< request bodies at once, 3 bytes per body byte (api::RouteOptions)
  std::string job_memory = "4GiB";     ///< running jobs at once, by their estimates (jobs::WorkerPoolOptions)
  std::string token;
  double job_timeout = 3600.0;
  int http_threads = 32;
  int max_attempts = 3;       ///< worker losses a job may cause before it is failed for good
  double lease = 30.0;        ///< s a running job's claim holds without renewal (jobs::WorkerPoolOptions)
};
CLI::App* add_serve_command(CLI::App& app, ServeOptions& options);
int run_serve(const ServeOptions& options);

}  // namespace manipid::server::cli

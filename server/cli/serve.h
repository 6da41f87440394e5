// serve.h — `manipid serve`: the HTTP service (store, worker pool, routes).
#pragma once

#include "cli/common.h"
#include "cli/job_options.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace manipid::server::cli {

struct ServeOptions {
  std::string host = "127.0.0.1";
  int port = 8080;
  JobOptions jobs;            ///< --db, --workers (0: API only), --job-memory, --job-timeout, --max-attempts, --lease
  int queue_limit = 10000;
  std::string max_body = "64MiB";
  std::string memory_budget = "1GiB";  ///< request bodies at once, 3 bytes per body byte (api::RouteOptions)
  std::string token;
  std::string token_file;     ///< --token-file: named tokens, each owner seeing its own (cli/token_file.h)
  int http_threads = 32;
  int max_connections_per_client = 64;  ///< connections waiting for a request head, per client address
  int max_connections = 4096;           ///< the same in all (at most half the open-file limit)
  int max_uploads_per_client = 16;      ///< request bodies being received at once, per client address
  int max_uploads = 256;                ///< the same in all
};
CLI::App* add_serve_command(CLI::App& app, ServeOptions& options);
int run_serve(const ServeOptions& options);

}  // namespace manipid::server::cli

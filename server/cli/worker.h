// worker.h — `manipid worker`: runs the jobs of a database and serves no HTTP (compute processes
// beside one or more `manipid serve --workers 0`).
#pragma once

#include "cli/job_options.h"

#include <CLI/CLI.hpp>

namespace manipid::server::cli {

struct WorkerOptions {
  JobOptions jobs;
};
CLI::App* add_worker_command(CLI::App& app, WorkerOptions& options);
int run_worker(const WorkerOptions& options);

}  // namespace manipid::server::cli

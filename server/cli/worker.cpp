// worker.cpp — `manipid worker`: opens the store (taking back the jobs a dead process of this
// machine left running), runs the worker pool until SIGINT/SIGTERM, then lets running jobs reach
// a safe point (they are queued again) and exits 0. Prints "working on DATABASE" first on stdout.
#include "cli/worker.h"

#include "cli/common.h"
#include "jobs/worker_pool.h"

#include <signal.h>

#include <cstdio>
#include <memory>
#include <string>

namespace manipid::server::cli {

CLI::App* add_worker_command(CLI::App& app, WorkerOptions& options) {
  CLI::App* command = app.add_subcommand(
      "worker",
      "Run the jobs of a database without serving HTTP: start one on each compute process beside "
      "'manipid serve --workers 0'. Prints 'working on DATABASE' first on stdout.");
  add_job_options(*command, options.jobs, 1);
  return command;
}

int run_worker(const WorkerOptions& options) {
  const jobs::WorkerPoolOptions pool_options = worker_pool_options(options.jobs);
  // Signals go to one thread that waits for them (sigwait below).
  sigset_t signals = block_stop_signals();

  const std::unique_ptr<store::Store> store = open_job_store(options.jobs);
  jobs::WorkerPool pool(*store, pool_options, log_line);
  pool.start();
  std::printf("working on %s\n", store::display_name(options.jobs.database).c_str());
  std::fflush(stdout);
  log_line("manipid " MANIPID_VERSION ": worker " + pool_options.owner + ", " + std::to_string(pool_options.workers) +
           " job thread(s), database " + store::display_name(options.jobs.database));
  int signal_number = 0;
  sigwait(&signals, &signal_number);
  log_line(std::string("manipid: ") + (signal_number == SIGINT ? "SIGINT" : "SIGTERM") +
           ": stopping (running jobs will be queued again)");
  pool.stop();
  log_line("manipid: stopped");
  return exit_success;
}

}  // namespace manipid::server::cli

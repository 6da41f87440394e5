// serve.cpp — `manipid serve`: the HTTP/JSON identification service. Owns the process: reads its
// named tokens (--token-file, cli/token_file.h), loads the HTTP module (manipid/api/http_endpoint.h),
// opens the store (recovering jobs a dead process left behind), starts the worker pool and the
// HTTP server, prints "listening on http://HOST:PORT" as its first line on stdout (so scripts and
// tests can start it on --port 0), and on SIGINT/SIGTERM stops accepting, lets running jobs reach
// a safe point (they are queued again) and exits 0.
#include "cli/serve.h"
#include "cli/token_file.h"
#include "jobs/job_service.h"
#include "store/store.h"
#include "jobs/worker_pool.h"

#include "manipid/api/http_endpoint.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace manipid::server::cli {

CLI::App* add_serve_command(CLI::App& app, ServeOptions& options) {
  CLI::App* command = app.add_subcommand(
      "serve",
      "Run the HTTP/JSON identification service: upload datasets, submit simulations and "
      "identifications, poll jobs. Prints 'listening on http://HOST:PORT' first on stdout.");
  command->add_option("--host", options.host, "Address to listen on (127.0.0.1: this machine only)")->capture_default_str();
  command->add_option("--port", options.port, "TCP port; 0 picks a free one")
      ->check(integer_between(0, 65535))
      ->capture_default_str();
  add_job_options(*command, options.jobs, 0);
  command->add_option("--idempotency-ttl", options.jobs.idempotency_ttl,
                      "Hours an Idempotency-Key is remembered: the same key sent again later makes a new job, "
                      "dataset or robot")
      ->check(CLI::Range(0.001, 8760.0))
      ->capture_default_str();
  command->add_option("--queue-limit", options.queue_limit, "Queued jobs at most; more get 429 (0: no limit)")
      ->check(integer_between(0, 100'000'000))
      ->capture_default_str();
  command->add_option("--max-body", options.max_body, "Largest request body (e.g. 64MiB, 500k)")->capture_default_str();
  command->add_option("--memory-budget", options.memory_budget,
                      "Memory the request bodies being handled at once may take, 3 bytes per body byte; "
                      "a body beyond it gets 503 and Retry-After (at least 3 x --max-body)")
      ->capture_default_str();
  command->add_option("--token", options.token,
                      "Bearer token every /v1 request and /metrics must carry (or MANIPID_TOKEN): one token that sees "
                      "and acts on everything")
      ->envname("MANIPID_TOKEN");
  command->add_option("--token-file", options.token_file,
                      "Named tokens (or MANIPID_TOKEN_FILE), one a line: NAME TOKEN, NAME:TOKEN, or admin NAME TOKEN; "
                      "'#' comments. Each dataset, robot and job is its creator's name's; a token sees its own only "
                      "(others' answer 404, as missing), an admin token everyone's and /metrics. Tokens at least 16 "
                      "characters; the file not readable by other users (chmod 600). Not with --token")
      ->envname("MANIPID_TOKEN_FILE");
  command->add_option("--http-threads", options.http_threads,
                      "Requests served at once (connections waiting for a request, and bodies being received, "
                      "hold no thread of these)")
      ->check(integer_between(2, 1024))
      ->capture_default_str();
  command->add_option("--max-connections-per-client", options.max_connections_per_client,
                      "Connections from one client address that may wait for a request (new, or idle between "
                      "requests); a new one beyond closes that address's oldest waiting one")
      ->check(integer_between(1, 1'000'000))
      ->capture_default_str();
  command->add_option("--max-connections", options.max_connections,
                      "Connections that may wait for a request, from all clients (at most half the open-file "
                      "limit); a new one beyond closes the oldest waiting one")
      ->check(integer_between(1, 10'000'000))
      ->capture_default_str();
  command->add_option("--max-uploads-per-client", options.max_uploads_per_client,
                      "Request bodies from one client address received at once; more get 503 and Retry-After")
      ->check(integer_between(1, 100'000))
      ->capture_default_str();
  command->add_option("--max-uploads", options.max_uploads,
                      "Request bodies received at once, from all clients; more get 503 and Retry-After")
      ->check(integer_between(1, 100'000))
      ->capture_default_str();
  return command;
}

int run_serve(const ServeOptions& options) {
  if (!options.token.empty() && !options.token_file.empty()) {
    throw UsageError("--token (MANIPID_TOKEN) and --token-file (MANIPID_TOKEN_FILE) both given: use one; an admin line "
                     "in the file (admin NAME TOKEN) is a token that sees everything");
  }
  // Read and checked first: a server whose tokens are wrong touches nothing.
  const std::vector<api::NamedToken> tokens =
      options.token_file.empty() ? std::vector<api::NamedToken>{} : read_token_file(options.token_file);
  const std::size_t max_body = parse_size(options.max_body, "--max-body");
  const std::size_t memory_budget = parse_size(options.memory_budget, "--memory-budget");
  if (memory_budget / api::memory_per_body_byte < max_body) {
    throw UsageError("--memory-budget: at least " + std::to_string(api::memory_per_body_byte) +
                     " x --max-body, so that any body fits alone (" + std::to_string(max_body * api::memory_per_body_byte) +
                     " bytes), got '" + options.memory_budget + "'");
  }
  const jobs::WorkerPoolOptions pool_options = worker_pool_options(options.jobs);
  try {
    api::load_http_module();  // before the store is opened: a server that cannot serve touches nothing
  } catch (const std::runtime_error& error) {
    throw OutputError(error.what());
  }

  // Signals go to one thread that waits for them (sigwait below).
  sigset_t signals = block_stop_signals();

  const std::unique_ptr<store::Store> store = open_job_store(options.jobs, options.http_threads);
  jobs::WorkerPool pool(*store, pool_options, log_line);
  jobs::JobService service(*store, pool, jobs::JobServiceOptions{options.queue_limit, log_line});

  api::HttpSettings http;
  http.threads = static_cast<std::size_t>(std::max(options.http_threads, 1));
  http.max_connections_per_client = static_cast<std::size_t>(options.max_connections_per_client);
  http.max_connections = static_cast<std::size_t>(options.max_connections);
  http.max_uploads_per_client = static_cast<std::size_t>(options.max_uploads_per_client);
  http.max_uploads = static_cast<std::size_t>(options.max_uploads);
  http.routes.max_body = max_body;
  http.routes.memory_budget = memory_budget;
  http.routes.token = options.token;
  http.routes.tokens = tokens;
  http.routes.log = log_line;
  http.routes.max_waiters = std::max(options.http_threads / 2, 1);
  const std::unique_ptr<api::HttpEndpoint> endpoint = api::open_http_endpoint(service, http);
  api::HttpEndpoint& server = *endpoint;

  const int port = server.bind(options.host, options.port);
  if (port <= 0) {
    throw OutputError("cannot listen on " + options.host + ":" + std::to_string(options.port) +
                      " (address in use, or not an address of this machine)");
  }

  pool.start();
  const auto admins = std::count_if(tokens.begin(), tokens.end(), [](const api::NamedToken& named) { return named.admin; });
  std::printf("listening on http://%s:%d\n", options.host.c_str(), port);
  std::fflush(stdout);
  log_line("manipid " MANIPID_VERSION ": listening on http://" + options.host + ":" + std::to_string(port) + ", " +
           (pool_options.workers == 0 ? std::string("no job threads (API only)")
                                      : std::to_string(pool_options.workers) + " worker(s)") +
           ", database " + store::display_name(options.jobs.database) +
           (options.token.empty() ? "" : ", bearer token required") +
           (tokens.empty() ? "" : ", " + std::to_string(tokens.size()) + " named tokens required (" + std::to_string(admins) +
                                      " admin)"));

  std::atomic<bool> listen_returned{false};
  std::thread signal_thread([&] {
    int signal_number = 0;
    sigwait(&signals, &signal_number);
    if (!listen_returned) {
      log_line(std::string("manipid: ") + (signal_number == SIGINT ? "SIGINT" : "SIGTERM") +
               ": shutting down (running jobs will be queued again)");
    }
    service.stop_accepting();
    pool.notify_changed();  // long-polls return now
    // cpp-httplib 0.11.4's stop() does nothing until listen has started.
    while (!server.is_running() && !listen_returned) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    // Stops listening and shuts every open connection down: 0.11.4's own stop() waits for
    // each HTTP thread's client, and a trickling client never finishes.
    server.stop_and_disconnect();
  });

  bool listened = false;
  std::string failure;
  try {
    listened = server.listen_after_bind();
  } catch (const std::exception& error) {
    // Its HTTP threads could not all be started (std::system_error: a thread or memory limit).
    failure = std::string("cannot start ") + std::to_string(options.http_threads) + " HTTP threads (" + error.what() +
              "); lower --http-threads or raise the limit";
    log_line("manipid: " + failure);
  }
  listen_returned = true;
  service.stop_accepting();
  pthread_kill(signal_thread.native_handle(), SIGTERM);  // wakes sigwait if no signal came
  signal_thread.join();
  pool.stop();
  log_line("manipid: stopped");
  if (!failure.empty()) throw OutputError(failure);
  return listened ? exit_success : exit_failure;
}

}  // namespace manipid::server::cli

// main.cpp — the `manipid` executable: parses the command line with CLI11, dispatches to one
// run function per subcommand (cli/NAME.h), and turns every failure into one line on stderr
// ("manipid: error: ...") and an exit status: 0 success, 2 usage or input error, 1 otherwise.
#include "cli/doctor.h"
#include "cli/excitation.h"
#include "cli/filter.h"
#include "cli/identify.h"
#include "cli/payload.h"
#include "cli/serve.h"
#include "cli/simulate.h"
#include "cli/torque.h"
#include "cli/worker.h"

#include "manipid/core/paper/identification.h"

#include <malloc.h>

#include <cstdio>
#include <exception>
#include <new>
#include <string>

#ifndef MANIPID_VERSION
#define MANIPID_VERSION "unknown"
#endif

namespace manipid::server::cli {
namespace {

int report(std::string message, int status) {
  // One line, whatever a file name or a quoted field contained.
  for (char& character : message) {
    if (character == '\n' || character == '\r') character = ' ';
  }
  std::fprintf(stderr, "manipid: error: %s\n", message.c_str());
  return status;
}

// A one-shot command (everything but serve and worker) allocates and frees its large arrays —
// the CSV text, the trajectory, the filtered signals, the regressor blocks — several times
// over. glibc's defaults give each array above 128 KiB fresh pages from the kernel and hand
// freed ones back, so the next array faults them in again: ~1,000 page faults and ~1.5 ms of a
// 20 ms `manipid identify` (perf stat). Such a process keeps what it frees until it exits.
// The services keep the defaults, which return memory between jobs.
void keep_freed_memory() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest: arrays up to 32 MiB come from the heap
  mallopt(M_TRIM_THRESHOLD, 1 << 30);   // and the heap is not trimmed while the command runs
}

int run(int argc, char** argv) {
  CLI::App app("manipid: identification of manipulator dynamic parameters with the input-error "
               "method (Cedro & Janecki). Units are SI; CSV files have a header row of column names.",
               "manipid");
  app.set_version_flag("--version", std::string("manipid ") + MANIPID_VERSION);

  SimulateOptions simulate;
  TorqueOptions torque;
  FilterOptions filter;
  IdentifyOptions identify;
  PayloadOptions payload;
  ServeOptions serve;
  ExcitationOptions excitation;
  DoctorOptions doctor;
  WorkerOptions worker;
  CLI::App* simulate_command = add_simulate_command(app, simulate);
  CLI::App* torque_command = add_torque_command(app, torque);
  CLI::App* filter_command = add_filter_command(app, filter);
  CLI::App* identify_command = add_identify_command(app, identify);
  CLI::App* payload_command = add_payload_command(app, payload);
  CLI::App* serve_command = add_serve_command(app, serve);
  CLI::App* excitation_command = add_excitation_command(app, excitation);
  CLI::App* doctor_command = add_doctor_command(app, doctor);
  CLI::App* worker_command = add_worker_command(app, worker);
  const CLI::App* commands[] = {simulate_command, torque_command,     filter_command, identify_command, payload_command,
                                serve_command,    excitation_command, doctor_command, worker_command};

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForAllHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForVersion& version) {
    return app.exit(version);
  } catch (const CLI::ParseError& error) {
    // Point at the help of the command being parsed, if any got that far.
    std::string help = "manipid --help";
    bool in_command = false;
    for (const CLI::App* command : commands) {
      if (command->parsed()) {
        help = "manipid " + command->get_name() + " --help";
        in_command = true;
      }
    }
    // CLI11 calls a mistyped command an unexpected argument; say what the user meant.
    if (!in_command && argc > 1 && argv[1][0] != '-') {
      return report(std::string("unknown command '") + argv[1] +
                        "'; expected simulate, torque, filter, identify, payload, serve, worker, excitation or doctor (see 'manipid --help')",
                    exit_usage);
    }
    return report(std::string(error.what()) + " (see '" + help + "')", exit_usage);
  }

  if (!serve_command->parsed() && !worker_command->parsed()) keep_freed_memory();
  if (simulate_command->parsed()) return run_simulate(simulate);
  if (torque_command->parsed()) return run_torque(torque);
  if (filter_command->parsed()) return run_filter(filter);
  if (identify_command->parsed()) return run_identify(identify);
  if (payload_command->parsed()) return run_payload(payload);
  if (serve_command->parsed()) return run_serve(serve);
  if (worker_command->parsed()) return run_worker(worker);
  if (excitation_command->parsed()) return run_excitation(excitation);
  if (doctor_command->parsed()) return run_doctor(doctor);
  return report("no command given; expected simulate, torque, filter, identify, payload, serve, worker, excitation or doctor (see 'manipid --help')", exit_usage);
}

}  // namespace
}  // namespace manipid::server::cli

int main(int argc, char** argv) {
  using namespace manipid::server::cli;
  // Every failure becomes one line and a status; nothing escapes as an abort.
  try {
    return run(argc, argv);
  } catch (const manipid::InputError& error) {
    return report(error.what(), exit_usage);
  } catch (const manipid::IdentificationError& error) {
    return report(error.what(), exit_usage);  // the starting values or the data leave no finite cost
  } catch (const UsageError& error) {
    return report(error.what(), exit_usage);
  } catch (const OutputError& error) {
    return report(error.what(), exit_failure);
  } catch (const std::bad_alloc&) {
    return report("out of memory", exit_failure);
  } catch (const std::exception& error) {
    return report(std::string("internal error: ") + error.what(), exit_failure);
  } catch (...) {
    return report("internal error: unknown exception", exit_failure);
  }
}

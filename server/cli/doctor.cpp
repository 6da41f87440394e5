// doctor.cpp — `manipid doctor --db FILE`: PRAGMA integrity_check and foreign_key_check of a
// service database (store/sqlite/store.h, check_file), for when `serve` refused a damaged file
// or before trusting a restored backup, and the rows whose text is not UTF-8 (stored before the
// service refused such text). Reads only: no migration, no WAL switch.
#include "cli/doctor.h"

#include "cli/common.h"
#include "store/sqlite/store.h"

#include <cstdio>
#include <string>

namespace manipid::server::cli {

CLI::App* add_doctor_command(CLI::App& app, DoctorOptions& options) {
  CLI::App* command = app.add_subcommand(
      "doctor", "Check a service database file in full (every page, index and reference) and say what is wrong");
  command->add_option("--db", options.database, "The SQLite file `manipid serve --db` uses (PATH or sqlite:PATH)")
      ->required();
  return command;
}

int run_doctor(const DoctorOptions& options) {
  std::string path;
  store::sqlite::FileCheck check;
  try {
    path = store::sqlite_path(options.database);
    check = store::sqlite::check_file(path);
  } catch (const store::StoreError& error) {
    throw UsageError(std::string("--db: ") + error.what());
  }
  if (check.findings.empty() && check.text_findings.empty()) {
    std::printf("%s: sound (schema version %d; PRAGMA integrity_check and foreign_key_check found nothing)\n",
                path.c_str(), check.schema_version);
    return exit_success;
  }
  if (check.findings.empty()) {
    std::printf("%s: sound (schema version %d), but %zu row(s)%s hold text that is not UTF-8, stored before the "
                "service refused it; it shows them with U+FFFD:\n",
                path.c_str(), check.schema_version, check.text_findings.size(),
                check.text_findings.size() >= 100 ? " (the first 100)" : "");
    for (const std::string& finding : check.text_findings) std::printf("  - %s\n", finding.c_str());
    std::printf("manipid serve runs on it: delete those rows (DELETE /v1/datasets/ID, /v1/robots/ID) and upload them "
                "again with UTF-8 names\n");
    return exit_failure;
  }
  std::printf("%s: damaged, %zu finding(s)%s:\n", path.c_str(), check.findings.size(),
              check.findings.size() >= 100 ? " (the first 100)" : "");
  for (const std::string& finding : check.findings) std::printf("  - %s\n", finding.c_str());
  std::printf("manipid serve will not start on it: restore the file from a backup\n");
  return exit_failure;
}

}  // namespace manipid::server::cli

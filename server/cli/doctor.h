// doctor.h — `manipid doctor`: a full integrity check of a service database, changing nothing.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace manipid::server::cli {

struct DoctorOptions {
  std::string database;  ///< --db FILE (required): an existing SQLite file, PATH or sqlite:PATH
};
CLI::App* add_doctor_command(CLI::App& app, DoctorOptions& options);
/// 0 when the file is sound, 1 when it is damaged (the findings on stdout), 2 when it is missing.
int run_doctor(const DoctorOptions& options);

}  // namespace manipid::server::cli

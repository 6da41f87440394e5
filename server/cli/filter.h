// filter.h — `manipid filter`: the paper's differential filters applied to a CSV.
#pragma once

#include "cli/common.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace manipid::server::cli {

struct FilterOptions {
  int order = 0;
  int half_length = 100;
  double band = 0.2;
  std::optional<double> dt;
  std::string input;
  std::string output = "-";
};
CLI::App* add_filter_command(CLI::App& app, FilterOptions& options);
int run_filter(const FilterOptions& options);

}  // namespace manipid::server::cli

// filter.cpp — `manipid filter`: applies the paper's differential filter (low-pass,
// first or second derivative) to every column of a CSV but `t`, keeping only the valid
// outputs; the t column, when present, is re-aligned to each output's centre sample.
#include "cli/filter.h"

#include "manipid/api/csv.h"
#include "manipid/core/signal/filters.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>

namespace manipid::server::cli {
namespace {

// The same rule as Trajectory::validate: steps equal to t[1] − t[0] within 1e-6 relative.
constexpr double time_tolerance = 1e-6;

std::string number(double value) {
  std::ostringstream text;
  text.precision(12);
  text << value;
  return text.str();
}

/// The sample period of a time column; throws InputError("t") unless it increases uniformly.
double time_step(const Eigen::VectorXd& t) {
  const double period = t[1] - t[0];
  for (Eigen::Index i = 1; i < t.size(); ++i) {
    const double step = t[i] - t[i - 1];
    if (!(step > 0.0)) {
      throw InputError("t", "t is not strictly increasing at data row " + std::to_string(i + 1) +
                                " (t = " + number(t[i]) + " s)");
    }
    if (std::abs(step - period) > time_tolerance * period) {
      throw InputError("t", "t is not uniformly sampled at data row " + std::to_string(i + 1) + " (t = " +
                                number(t[i]) + " s): the step is " + number(step) + " s but t[1] - t[0] = " +
                                number(period) + " s");
    }
  }
  return period;
}

std::string filter_option(const std::string& field) {
  if (field == "half_length") return "--half-length";
  if (field == "band") return "--band";
  if (field == "dt") return "--dt";
  return "filter";
}

}  // namespace

CLI::App* add_filter_command(CLI::App& app, FilterOptions& options) {
  CLI::App* command = app.add_subcommand(
      "filter",
      "Apply the paper's differential filter (Filtr, Filtr1, Filtr2) to every column but t. "
      "For N input rows the output has N - 2M - 1 rows; output row j is centred on input row M + j.");
  command->add_option("--order", options.order, "0 low-pass, 1 first derivative, 2 second derivative")
      ->required()
      ->check(integer_between(0, 2));
  command->add_option("--half-length", options.half_length, "M: the filter has 2M + 1 taps")
      ->check(integer_between(2, 1'000'000))
      ->capture_default_str();
  command->add_option("--band", options.band, "Band edge Omega_g in rad/sample, in (0, pi]")
      ->check(positive_number())
      ->capture_default_str();
  command->add_option("--dt", options.dt, "Sample period in s (default: the spacing of the t column)")
      ->check(positive_number());
  command->add_option("--in", options.input, "Input CSV file, '-' for stdin")->required();
  command->add_option("--out", options.output, "Output CSV file, '-' for stdout")->capture_default_str();
  return command;
}

int run_filter(const FilterOptions& options) {
  const api::CsvTable input = read_table(options.input);
  const std::string source = input_name(options.input);
  const int time_column = input.column_index("t");

  if (static_cast<int>(input.columns.size()) - (time_column >= 0 ? 1 : 0) == 0) {
    throw InputError("csv", source + ": no columns to filter (every column but t is filtered)");
  }

  // Δ: the option, the t column's spacing, and the two must agree when both are given.
  double dt = 0.0;
  if (time_column >= 0 && input.rows() >= 2) {
    try {
      dt = time_step(input.data.col(time_column));
    } catch (const InputError& error) {
      rethrow_with_source(error, source);
    }
    if (options.dt && std::abs(*options.dt - dt) > time_tolerance * dt) {
      throw InputError("dt", "--dt " + number(*options.dt) +
                                 " s does not match the spacing of the t column in " + source + " (" +
                                 number(dt) + " s)");
    }
  }
  if (options.dt) dt = *options.dt;

  FilterSettings settings;
  settings.half_length = options.half_length;
  settings.band = options.band;
  settings.dt = dt > 0.0 ? dt : 1.0;  // a placeholder until we know the input is long enough
  try {
    settings.validate();
  } catch (const InputError& error) {
    rethrow_with_source(error, filter_option(error.field()));
  }
  const int outputs = DifferentialFilter::output_length(static_cast<int>(input.rows()), settings.half_length);
  if (outputs < 1) {
    throw InputError("samples", source + ": the filter with --half-length " +
                                    std::to_string(settings.half_length) + " needs at least 2M+2 = " +
                                    std::to_string(DifferentialFilter::min_input_samples(settings.half_length)) + " rows, got " +
                                    std::to_string(input.rows()));
  }
  if (!(dt > 0.0)) {
    throw UsageError("--dt is required when the input has no t column (" + source + ")");
  }
  settings.dt = dt;
  std::shared_ptr<const DifferentialFilter> filter;
  try {
    filter = cached_filter(settings);
  } catch (const InputError& error) {
    rethrow_with_source(error, filter_option(error.field()));
  }

  const FilterOrder order = static_cast<FilterOrder>(options.order);
  const int first = filter->first_output_index();
  api::CsvTable output;
  output.columns = input.columns;
  output.data.resize(outputs, input.data.cols());
  for (Eigen::Index column = 0; column < input.data.cols(); ++column) {
    if (column == time_column) {
      output.data.col(column) = input.data.col(column).segment(first, outputs);
    } else {
      filter->apply(order, input.data.col(column), output.data.col(column));
    }
  }

  write_table(options.output, output);
  std::fprintf(stderr,
               "manipid filter: order %d, M = %d, band %g rad/sample, dt = %g s: %d rows -> %d rows "
               "(output row j is input row M + j) -> %s\n",
               options.order, settings.half_length, settings.band, settings.dt, input.rows(), outputs,
               output_name(options.output).c_str());
  return exit_success;
}

}  // namespace manipid::server::cli

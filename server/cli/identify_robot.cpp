// identify_robot.cpp — `manipid identify DATA.csv --robot R.urdf`: a URDF robot's base
// parameters by linear input-error, printed as a table (base parameters, friction, consistency, fit,
// validation) or, with --json, as the result object (api/robot_json.h).
#include "cli/identify.h"

#include "manipid/api/csv.h"
#include "manipid/api/robot_json.h"
#include "manipid/core/robot/identification.h"
#include "manipid/core/robot/urdf_writer.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

namespace manipid::server::cli {
namespace {

std::string percent(double value) { return std::isfinite(value) ? format(100.0 * value, 3) + " %" : "-"; }

std::string hertz(const FilterSettings& filter) { return format(filter.band / (2.0 * std::numbers::pi * filter.dt), 3) + " Hz"; }

/// "auto" → 0, else an integer / a number (the option's name in errors).
int half_length_option(const std::string& text, const std::string& option) {
  return text == "auto" ? 0 : static_cast<int>(parse_integer_option(text, option, 2, 1'000'000));
}
double band_option(const std::string& text, const std::string& option) {
  if (text == "auto") return 0.0;
  const double band = parse_number_option(text, option);
  if (!(band > 0.0 && band <= std::numbers::pi)) throw InputError(option, option + " must lie in (0, pi] rad/sample");
  return band;
}

Trajectory read_trajectory(const std::string& path) {
  try {
    return api::trajectory_from_csv(read_table(path), true);
  } catch (const InputError& error) {
    rethrow_with_source(error, input_name(path));
  }
}

void print_prediction_row(const char* label, const robot::TorquePrediction& prediction) {
  std::printf("  %-22s", label);
  for (Eigen::Index k = 0; k < prediction.relative_error.size(); ++k) std::printf(" %8s", percent(prediction.relative_error[k]).c_str());
  std::printf("   overall %s\n", percent(prediction.overall_relative_error).c_str());
}

void print_table(const robot::Model& model, const robot::ParameterLayout& layout, const robot::IdentificationResult& result,
                 const robot::TorquePrediction& fit, const std::optional<robot::ValidationReport>& validation,
                 const std::string& data_name, const std::string& validation_name) {
  const int n = model.joint_count();
  std::string terms;
  for (const std::string& term : api::friction_names(layout)) terms += (terms.empty() ? "" : ", ") + term;
  std::printf("robot %s: %d joints (%s .. %s); friction per joint: %s%s\n", model.name.c_str(), n,
              model.joints.front().name.c_str(), model.joints.back().name.c_str(), terms.empty() ? "none" : terms.c_str(),
              layout.armature ? "; armature" : "");
  const robot::FilterPair& filters = result.filters;
  std::printf("input-error, linear least squares on %s: %d rows (1 in %d filtered instants x %d joints), %d base parameters, "
              "condition number %s\n",
              data_name.c_str(), result.rows, result.decimation, n, result.base.size(), format(result.condition_number, 3).c_str());
  std::printf("filters%s: differentiation M = %d, band %s rad/sample (%s); comparison M = %d, band %s rad/sample (%s)",
              result.filters_chosen_automatically ? " (chosen from the data)" : "", filters.differentiation.half_length,
              format(filters.differentiation.band, 4).c_str(), hertz(filters.differentiation).c_str(),
              filters.comparison.half_length, format(filters.comparison.band, 4).c_str(), hertz(filters.comparison).c_str());
  if (result.motion_band_hz > 0) std::printf("; motion band %s Hz", format(result.motion_band_hz, 3).c_str());
  std::printf("\n\n%-60s %14s %12s %9s\n", "base parameter", "estimate", "std error", "rel std");
  for (int i = 0; i < result.base.size(); ++i) {
    const double estimate = result.estimate[i], error = result.std_errors[i];
    std::string name = result.base.names[static_cast<std::size_t>(i)];
    if (name.size() > 60) name = name.substr(0, 57) + "...";
    std::printf("%-60s %14s %12s %9s\n", name.c_str(), format(estimate).c_str(), format(error, 3).c_str(),
                estimate != 0.0 ? percent(std::abs(error / estimate)).c_str() : "-");
  }
  if (layout.viscous || layout.coulomb || layout.offset || layout.armature) {
    std::printf("\n%-24s %12s %12s %12s%s\n", "friction (point)", layout.viscous ? "fv" : "", layout.coulomb ? "fc" : "",
                layout.offset ? "fo" : "", layout.armature ? "           Ia" : "");
    for (int k = 0; k < n; ++k) {
      const auto value = [&](int begin) { return begin >= 0 ? format(result.point[begin + k], 4) : std::string(); };
      std::printf("%-24s %12s %12s %12s", model.joints[static_cast<std::size_t>(k)].name.c_str(),
                  value(layout.viscous_begin(n)).c_str(), value(layout.coulomb_begin(n)).c_str(),
                  value(layout.offset_begin(n)).c_str());
      if (layout.armature) std::printf(" %12s", value(layout.armature_begin(n)).c_str());
      std::printf("\n");
    }
  }
  if (!result.unidentifiable.empty()) {
    std::string names;
    for (const std::string& name : result.unidentifiable) names += (names.empty() ? "" : ", ") + name;
    std::printf("\nnever in the torque (not identifiable; kept at the URDF's values): %s\n", names.c_str());
  }
  if (result.consistency.consistent()) {
    std::printf("\nphysically consistent: every link a real rigid body%s\n",
                layout.viscous || layout.coulomb || layout.armature ? ", every friction term >= 0" : "");
  } else {
    std::printf("\nnot physically consistent (identify with --physical for an estimate that is):\n");
    for (const std::string& finding : result.consistency.findings) std::printf("  - %s\n", finding.c_str());
  }
  if (result.physical) std::printf("physical fit: %s\n", result.physical->brief_report().c_str());
  std::printf("\nrelative error of the filtered torque, per joint (%s .. %s):\n", model.joints.front().name.c_str(),
              model.joints.back().name.c_str());
  print_prediction_row(("fit, " + data_name).substr(0, 22).c_str(), fit);
  if (validation) {
    print_prediction_row("validation, estimate", validation->estimate);
    print_prediction_row("validation, URDF", validation->prior);
    std::printf("  (validation data: %s)\n", validation_name.c_str());
  }
  std::printf("\n%.3f s\n", result.wall_seconds);
  for (const std::string& warning : result.warnings) std::printf("\nwarning: %s\n", warning.c_str());
  if (validation) {
    for (const std::string& warning : validation->warnings) std::printf("\nwarning (validation data): %s\n", warning.c_str());
  }
}

}  // namespace

int run_identify_robot(const IdentifyOptions& options) {
  if (options.method != "input-error") {
    throw UsageError("--method " + options.method +
                     ": output-error and two-stage identify the paper's point-mass model (--preset); a URDF robot is "
                     "identified by the input-error method, which is linear in its parameters");
  }
  if (options.weights == "inverse-variance") {
    throw UsageError("--weights: a URDF robot takes unit or per-joint (each joint by its residual's variance)");
  }
  const robot::ParsedUrdf parsed_urdf = load_urdf_robot(options.urdf);
  const robot::Model& model = parsed_urdf.model;
  robot::IdentificationOptions identification;
  identification.layout = parameter_layout(options.friction, options.armature);
  identification.weighting =
      options.weights == "per-joint" ? robot::JointWeighting::per_joint : robot::JointWeighting::unit;
  identification.physical = options.physical;
  if (!options.trim.empty()) {
    const auto comma = options.trim.find(',');
    if (comma == std::string::npos) throw InputError("trim", "--trim needs START,END: the seconds dropped at each end");
    identification.preparation.trim_start = parse_number_option(options.trim.substr(0, comma), "--trim");
    identification.preparation.trim_end = parse_number_option(options.trim.substr(comma + 1), "--trim");
  }
  identification.preparation.uniform.dt = options.dt;
  identification.half_length = half_length_option(options.half_length, "--half-length");
  identification.band = band_option(options.band, "--band");
  identification.comparison_half_length = half_length_option(options.comparison_half_length, "--comparison-half-length");
  identification.comparison_band = band_option(options.comparison_band, "--comparison-band");

  const Trajectory data = read_trajectory(options.input);
  robot::IdentificationResult result;
  try {
    result = robot::identify(model, data, identification);
  } catch (const InputError& error) {
    rethrow_with_source(error, input_name(options.input));
  }
  std::optional<Trajectory> storage;
  const Trajectory& prepared = prepare_data(data, identification.preparation, storage);
  const robot::TorquePrediction fit = robot::predict_torque(model, identification.layout, result.point, prepared, result.filters);
  std::optional<robot::ValidationReport> validation;
  if (!options.validate.empty()) {
    const Trajectory second = read_trajectory(options.validate);
    try {
      validation = robot::validate(model, identification.layout, result, second, identification.preparation);
    } catch (const InputError& error) {
      rethrow_with_source(error, input_name(options.validate));
    }
  }
  // The URDF's warnings once the call is known to work: a refused call prints one line.
  print_urdf_warnings(options.urdf, parsed_urdf);
  if (!options.write_urdf.empty()) {
    try {
      write_text(options.write_urdf,
                 robot::write_identified_urdf(read_text(options.urdf.urdf), model, identification.layout, result.point));
    } catch (const InputError& error) {
      rethrow_with_source(error, "--write-urdf");
    }
  }
  if (options.json) {
    std::printf("%s\n", api::robot_result_to_json(model, identification.layout, result, fit, validation).dump(2).c_str());
  } else {
    print_table(model, identification.layout, result, fit, validation, input_name(options.input), input_name(options.validate));
  }
  return exit_success;
}

}  // namespace manipid::server::cli

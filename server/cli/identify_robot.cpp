// identify_robot.cpp — `manipid identify DATA.csv --robot R.urdf`: a URDF robot's base
// parameters by linear input-error, printed as a table (base parameters, friction, consistency, fit,
// validation) or, with --json, as the result object (api/robot_json.h).
#include "cli/identify.h"

#include "manipid/api/csv.h"
#include "manipid/api/robot_identification_run.h"
#include "manipid/api/robot_json.h"
#include "manipid/core/robot/identification.h"
#include "manipid/core/robot/link_table.h"
#include "manipid/core/robot/urdf_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

namespace manipid::server::cli {
namespace {

std::string percent(double value) { return std::isfinite(value) ? format(100.0 * value, 3) + " %" : "-"; }

std::string hertz(const FilterSettings& filter) { return format(filter.band / (2.0 * std::numbers::pi * filter.dt), 3) + " Hz"; }

/// "auto" → `automatic`, else a number (the option's name in errors).
double number_or_auto(const std::string& text, const std::string& option, double automatic) {
  return text == "auto" ? automatic : parse_number_option(text, option);
}

void print_prediction_rows(const char* label, const robot::TorquePrediction& prediction) {
  std::printf("  %-22s", label);
  for (Eigen::Index k = 0; k < prediction.relative_error.size(); ++k) std::printf(" %9s", percent(prediction.relative_error[k]).c_str());
  std::printf("   overall %s\n", percent(prediction.overall_relative_error).c_str());
  std::printf("  %-22s", "  (N m RMS)");
  for (Eigen::Index k = 0; k < prediction.rms_error.size(); ++k) std::printf(" %9s", format(prediction.rms_error[k], 3).c_str());
  std::printf("\n");
}

void print_table(const robot::Model& model, const robot::IdentificationResult& result,
                 const std::optional<robot::ValidationReport>& validation, const std::string& data_name,
                 const std::string& validation_name) {
  const int n = model.joint_count();
  const robot::ParameterLayout& layout = result.layout;
  std::printf("robot %s: %d joints (%s .. %s); friction per joint: %s%s\n", model.name.c_str(), n,
              model.joints.front().name.c_str(), model.joints.back().name.c_str(), robot::friction_text(layout).c_str(),
              layout.armature ? "; armature" : "");
  const robot::FilterPair& filters = result.filters;
  std::printf("input-error, linear least squares on %s: %d rows from %d joint%s, %d base parameters, condition number %s\n",
              data_name.c_str(), result.rows, static_cast<int>(result.torque_joints.size()),
              result.torque_joints.size() == 1 ? "" : "s", result.base.size(), format(result.condition_number, 3).c_str());
  std::printf("filters: differentiation M = %d, band %s rad/sample (%s); comparison: zero-phase Butterworth at %s Hz; "
              "ridge toward the URDF %s\n",
              filters.differentiation.half_length, format(filters.differentiation.band, 4).c_str(),
              hertz(filters.differentiation).c_str(), format(filters.comparison_cutoff_hz, 3).c_str(),
              format(result.ridge, 3).c_str());
  if (result.chosen_by_held_out) {
    std::printf("chosen by held-out prediction (5-fold over time; relative error of the judge's low-passed torque):\n");
    for (const robot::CandidateScore& candidate : result.candidates) {
      const bool chosen = candidate.cutoff_hz == filters.comparison_cutoff_hz && candidate.friction == robot::friction_text(layout) &&
                          candidate.ridge == result.ridge;
      std::printf("  %s comparison %6s Hz, friction %-22s ridge %-8s held-out %s\n", chosen ? "*" : " ",
                  format(candidate.cutoff_hz, 3).c_str(), candidate.friction.c_str(), format(candidate.ridge, 2).c_str(),
                  percent(candidate.held_out_error).c_str());
    }
  }
  std::printf("\n%-60s %14s %12s %9s %6s\n", "base parameter", "estimate", "std error", "rel std", "data");
  for (int i = 0; i < result.base.size(); ++i) {
    const double estimate = result.estimate[i], error = result.std_errors[i];
    std::string name = result.base.names[static_cast<std::size_t>(i)];
    if (name.size() > 60) name = name.substr(0, 57) + "...";
    std::printf("%-60s %14s %12s %9s %5.0f%%\n", name.c_str(), format(estimate).c_str(), format(error, 3).c_str(),
                estimate != 0.0 ? percent(std::abs(error / estimate)).c_str() : "-", 100.0 * result.data_share[i]);
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
  // The links as the identified URDF holds them; "data" says what the runs determine of each.
  std::printf("\n%-20s %10s %27s %52s  %s\n", "link (point)", "mass kg", "centre of mass m: x y z",
              "inertia about it kg m^2: ixx ixy ixz iyy iyz izz", "determined by the data");
  for (const robot::LinkRow& row : robot::link_table(model, result)) {
    const Eigen::Matrix3d& I = row.inertia_about_com;
    const char* seen = row.inertia_determined()             ? "all"
                       : row.centre_of_mass_determined()    ? "mass, centre of mass"
                       : row.mass_determined()              ? "mass"
                                                            : "only in combinations";
    std::printf("%-20s %10s %8s %8s %9s %8s %8s %8s %8s %8s %8s  %s%s\n", row.link.substr(0, 20).c_str(),
                format(row.mass, 4).c_str(), format(row.centre_of_mass.x(), 3).c_str(),
                format(row.centre_of_mass.y(), 3).c_str(), format(row.centre_of_mass.z(), 3).c_str(),
                format(I(0, 0), 3).c_str(), format(I(0, 1), 3).c_str(), format(I(0, 2), 3).c_str(),
                format(I(1, 1), 3).c_str(), format(I(1, 2), 3).c_str(), format(I(2, 2), 3).c_str(), seen,
                row.consistent ? "" : " (not a real body)");
  }
  if (!result.unidentifiable.empty()) {
    // Kept at the URDF's values — unless the physical fit had to move one to make its link a real body
    // (a link's mass must hold the first moments and inertia the data determine): said, so the text and
    // the written URDF agree.
    std::string kept, moved;
    for (const std::string& name : result.unidentifiable) {
      const auto at = std::find(result.standard_names.begin(), result.standard_names.end(), name);
      const Eigen::Index i = at - result.standard_names.begin();
      const bool same = at == result.standard_names.end() ||
                        std::abs(result.point[i] - result.prior[i]) <= 1e-9 * std::max(1.0, std::abs(result.prior[i]));
      if (same) {
        kept += (kept.empty() ? "" : ", ") + name;
      } else {
        moved += (moved.empty() ? "" : ", ") + name + " " + format(result.prior[i], 4) + " -> " + format(result.point[i], 4);
      }
    }
    std::printf("\nnever in the torque (not identifiable):\n");
    if (!kept.empty()) std::printf("  kept at the URDF's values: %s\n", kept.c_str());
    if (!moved.empty()) {
      std::printf("  moved by the physical fit, to make their links real bodies nearest the URDF's values: %s\n",
                  moved.c_str());
    }
  }
  if (result.consistency.consistent()) {
    std::printf("\nphysically consistent: every link a real rigid body%s\n",
                layout.viscous || layout.coulomb || layout.armature ? ", every friction term >= 0" : "");
  } else {
    std::printf("\nnot physically consistent (identify with --physical for an estimate that is):\n");
    for (const std::string& finding : result.consistency.findings) std::printf("  - %s\n", finding.c_str());
  }
  if (result.physical) std::printf("physical fit: %s\n", result.physical->brief_report().c_str());
  std::printf("\ntorque error judged under a zero-phase 4th-order Butterworth low-pass at %s Hz, %s s trimmed at each end "
              "(--judge-cutoff), per joint:\n  %-22s",
              format(result.judge.cutoff_hz, 3).c_str(), format(result.judge.trim_seconds, 3).c_str(), "");
  for (int k : result.torque_joints) std::printf(" %9s", model.joints[static_cast<std::size_t>(k)].name.substr(0, 9).c_str());
  std::printf("\n");
  print_prediction_rows("fit (training data)", result.fit);
  if (validation) {
    print_prediction_rows("validation, estimate", validation->estimate);
    print_prediction_rows("validation, URDF", validation->prior);
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
  if (!options.removed_option.empty()) {
    throw UsageError(options.removed_option + " no longer exists: the comparison low-pass is a zero-phase Butterworth filter, "
                     "set by --comparison-cutoff HZ (or auto: chosen by held-out prediction)");
  }
  const robot::ParsedUrdf parsed_urdf = load_urdf_robot(options.urdf);
  const robot::Model& model = parsed_urdf.model;
  robot::IdentificationOptions identification;
  identification.friction_auto = options.friction == "auto";
  identification.layout = parameter_layout(identification.friction_auto ? "viscous,coulomb,offset" : options.friction, options.armature);
  identification.weighting =
      options.weights == "per-joint" ? robot::JointWeighting::per_joint : robot::JointWeighting::unit;
  identification.physical = options.physical;
  identification.preparation = parse_trim(options.trim);
  identification.preparation.uniform.dt = options.dt;
  if ((options.half_length == "auto") != (options.band == "auto")) {
    throw UsageError("--half-length and --band set the differentiation filter together: give both, or neither");
  }
  if (options.half_length != "auto") {
    identification.half_length = static_cast<int>(parse_integer_option(options.half_length, "--half-length", 2, 1'000'000));
    identification.band = parse_number_option(options.band, "--band");
    if (!(identification.band > 0.0 && identification.band <= std::numbers::pi)) {
      throw InputError("--band", "--band must lie in (0, pi] rad/sample");
    }
  }
  identification.comparison_cutoff_hz = number_or_auto(options.comparison_cutoff, "--comparison-cutoff", 0.0);
  if (options.comparison_cutoff != "auto" && !(identification.comparison_cutoff_hz > 0.0)) {
    throw InputError("--comparison-cutoff", "--comparison-cutoff must be a positive number of Hz, or auto");
  }
  identification.ridge = number_or_auto(options.ridge, "--ridge", -1.0);
  if (options.ridge != "auto" && !(identification.ridge >= 0.0)) {
    throw InputError("--ridge", "--ridge must be a number >= 0 (0: plain least squares), or auto");
  }
  identification.judge.cutoff_hz = options.judge_cutoff;
  identification.judge.trim_seconds = options.judge_trim;
  if (!options.torque_joints.empty()) {
    identification.torque_joints = joint_list(options.torque_joints, model.joint_count(), "--torque-joints");
  }

  api::LogFormat log = options.log;
  for (const robot::Joint& joint : model.joints) log.joint_names.push_back(joint.name);  // what {joint} matches
  std::vector<Trajectory> runs;
  for (const std::string& path : options.inputs) runs.push_back(read_run(path, log, options.topic));
  const api::RobotIdentificationRun run = api::run_robot_identification(
      model, runs, identification,
      [&] {
        std::vector<Trajectory> held_out;
        for (const std::string& path : options.validate) held_out.push_back(read_run(path, log, options.topic));
        return held_out;
      },
      [&](api::RobotRunStep step, const InputError& error) {
        if (step == api::RobotRunStep::validate) rethrow_with_source(error, run_names(options.validate));
        // An option's value at fault is named by the option, anything else by the data it came from.
        for (const auto& [field, option] : {std::pair{"judge_cutoff", "--judge-cutoff"}, {"judge_trim", "--judge-trim"},
                                            {"comparison_cutoff", "--comparison-cutoff"}, {"torque_joints", "--torque-joints"},
                                            {"ridge", "--ridge"}, {"half_length", "--half-length"}, {"band", "--band"}}) {
          if (error.field() == field) rethrow_with_source(error, option);
        }
        rethrow_with_source(error, run_names(options.inputs));
      });
  const robot::IdentificationResult& result = run.result;
  const std::optional<robot::ValidationReport>& validation = run.validation;
  // The URDF's warnings once the call is known to work: a refused call prints one line.
  print_urdf_warnings(options.urdf, parsed_urdf);
  const nlohmann::ordered_json& json = run.json;
  // The URDF first (an estimate it cannot hold is said after the result, which is printed either way).
  std::string urdf_refused;
  if (!options.write_urdf.empty()) {
    try {
      const std::string note = api::identified_urdf_note(json, run_names(options.inputs));
      write_text(options.write_urdf, robot::write_identified_urdf(read_text(options.urdf.urdf), model, result.layout,
                                                                  result.point, note));
    } catch (const InputError& error) {
      if (error.field() != "parameters") rethrow_with_source(error, "--write-urdf");
      urdf_refused = error.what();
    }
  }
  if (options.json) {
    std::printf("%s\n", json.dump(2).c_str());
  } else {
    print_table(model, result, validation, run_names(options.inputs), run_names(options.validate));
  }
  if (!urdf_refused.empty()) {
    std::fflush(stdout);
    std::fprintf(stderr,
                 "manipid: error: --write-urdf: %s not written: %s. The result above stands; for a URDF, identify "
                 "again with --physical (every link a real rigid body, the data's fit as close as the bodies allow)\n",
                 options.write_urdf.c_str(), urdf_refused.c_str());
    return exit_usage;
  }
  return exit_success;
}

}  // namespace manipid::server::cli

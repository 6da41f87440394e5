// identification.cpp — base parameters by linear least squares on consistently filtered rows, with the
// comparison filter, the ridge and the friction terms chosen by held-out prediction (robot/identification.h).
#include "manipid/core/robot/identification.h"

#include "manipid/core/robot/link_table.h"

#include "manipid/core/errors.h"
#include "numbers.h"
#include "manipid/core/estimation/cross_validation.h"
#include "manipid/core/estimation/linear_least_squares.h"
#include "manipid/core/estimation/rules.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <chrono>
#include <functional>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

namespace manipid::robot {
namespace {

using Clock = std::chrono::steady_clock;

/// A base parameter whose data share is below this is reported as barely seen by the data.
constexpr double kBarelySeenShare = 0.5;
/// An estimate this many times its prior is named in a warning; for a prior of zero (below kRoundOff of the
/// largest prior: a rounded URDF angle's residue), an estimate whose torque alone is kCancelled times the
/// measured torque (others must cancel it: the signature of collinear columns).
constexpr double kFarFromPrior = 100.0;
constexpr double kRoundOff = 1e-9;
constexpr double kCancelled = 10.0;
/// A joint whose torque RMS is below this fraction of the largest joint's, in every run, is taken to have no
/// torque sensor (step 1).
constexpr double kNoTorqueRatio = 1e-4;

// (Not `join`: urdf.cpp has one with a separator, and a unity batch can hold both files.)
std::string join_words(const std::vector<std::string>& words) {
  std::string text;
  for (std::size_t i = 0; i < words.size(); ++i) text += (i ? ", " : "") + words[i];
  return text;
}

std::string percent(double share) {
  std::ostringstream text;
  text.precision(share < 0.1 ? 1 : 2);
  text << 100.0 * share << " %";
  return text.str();
}

/// π index in `full` of each parameter of `sub` (sub's terms are a subset of full's).
std::vector<int> layout_map(const ParameterLayout& sub, const ParameterLayout& full, int n) {
  std::vector<int> map;
  for (int i = 0; i < kInertialParametersPerBody * n; ++i) map.push_back(i);
  const auto add = [&](int sub_begin, int full_begin) {
    if (sub_begin < 0) return;
    for (int k = 0; k < n; ++k) map.push_back(full_begin + k);
  };
  add(sub.viscous_begin(n), full.viscous_begin(n));
  add(sub.coulomb_begin(n), full.coulomb_begin(n));
  add(sub.offset_begin(n), full.offset_begin(n));
  add(sub.armature_begin(n), full.armature_begin(n));
  return map;
}

/// The rows of every run stacked, with each row's run.
struct StackedRows {
  Eigen::MatrixXd W;
  Eigen::VectorXd tau;
  std::vector<int> run_of_row;
  std::vector<double> time_of_row;
  int row_step = 1;
  double lowpass_energy = 1.0;
};

StackedRows stack(std::vector<FilteredRows>&& per_run) {
  StackedRows stacked;
  if (per_run.size() == 1) {  // one run: its rows as they are
    FilteredRows& rows = per_run.front();
    const Eigen::Index J = static_cast<Eigen::Index>(rows.joints.size());
    for (Eigen::Index r = 0; r < rows.W.rows(); ++r) {
      stacked.run_of_row.push_back(0);
      stacked.time_of_row.push_back(rows.t[r / J]);
    }
    stacked.W = std::move(rows.W);
    stacked.tau = std::move(rows.tau);
    stacked.row_step = rows.row_step;
    stacked.lowpass_energy = rows.lowpass_energy;
    return stacked;
  }
  Eigen::Index total = 0;
  for (const FilteredRows& rows : per_run) total += rows.W.rows();
  const Eigen::Index p = per_run.front().W.cols();
  stacked.W.resize(total, p);
  stacked.tau.resize(total);
  Eigen::Index at = 0;
  for (std::size_t run = 0; run < per_run.size(); ++run) {
    const FilteredRows& rows = per_run[run];
    stacked.W.middleRows(at, rows.W.rows()) = rows.W;
    stacked.tau.segment(at, rows.tau.size()) = rows.tau;
    const Eigen::Index J = static_cast<Eigen::Index>(rows.joints.size());
    for (Eigen::Index r = 0; r < rows.W.rows(); ++r) {
      stacked.run_of_row.push_back(static_cast<int>(run));
      stacked.time_of_row.push_back(rows.t[r / J]);
    }
    at += rows.W.rows();
  }
  stacked.row_step = per_run.front().row_step;
  stacked.lowpass_energy = per_run.front().lowpass_energy;
  return stacked;
}

/// The warning naming every estimate far from its prior (an empty string when none is): an estimate
/// kFarFromPrior times its prior; or, for a prior of zero (to round-off: below kRoundOff of the largest), an
/// estimate whose torque alone is kCancelled times the measured torque, which the other parameters must cancel.
std::string far_from_prior(const BaseParameters& base, const Eigen::VectorXd& estimate, const Eigen::VectorXd& beta_prior,
                           const Eigen::MatrixXd& W_b, const Eigen::VectorXd& tau) {
  std::vector<std::string> far;
  const double torque_norm = tau.norm();
  const double largest_prior = beta_prior.cwiseAbs().maxCoeff();
  for (int i = 0; i < base.size(); ++i) {
    const double value = estimate[i], prior_value = beta_prior[i];
    const double column = W_b.col(i).norm();
    std::ostringstream text;
    text.precision(3);
    if (std::abs(prior_value) > kRoundOff * largest_prior) {
      const double ratio = std::abs(value / prior_value);
      if (ratio <= kFarFromPrior) continue;
      text << base.names[static_cast<std::size_t>(i)] << " = " << value << " (" << ratio << " times the URDF's "
           << prior_value << ")";
    } else {
      const double contribution = std::abs(value) * column / torque_norm;
      if (!(contribution > kCancelled)) continue;
      text << base.names[static_cast<std::size_t>(i)] << " = " << value << " (its torque alone " << contribution
           << " times the measured torque, cancelled by others)";
    }
    far.push_back(text.str());
  }
  if (far.empty()) return {};
  return "estimates far from the URDF's values: " + join_words(far) + "; check the URDF, the units and the excitation before "
         "trusting them";
}

/// The runs as the identification uses them (step 1: signal/resample.h's prepare_runs).
using Runs = PreparedRuns;

/// Step 1: the joints with a torque measurement.
std::vector<int> measured_joints(const Model& model, const Runs& runs, const std::vector<int>& given,
                                 std::vector<std::string>& warnings) {
  const int n = model.joint_count();
  if (!given.empty()) {
    std::vector<int> joints = given;
    std::sort(joints.begin(), joints.end());
    joints.erase(std::unique(joints.begin(), joints.end()), joints.end());
    for (int k : joints) {
      if (k < 0 || k >= n) {
        throw InputError("torque_joints", "joint " + std::to_string(k + 1) + " does not exist: the robot (" + model.name +
                                              ") has joints 1 to " + std::to_string(n));
      }
    }
    return joints;
  }
  Eigen::VectorXd largest_share = Eigen::VectorXd::Zero(n);
  for (const Trajectory& run : runs) {
    const Eigen::VectorXd rms = (run.tau.colwise().squaredNorm() / static_cast<double>(run.samples())).cwiseSqrt().transpose();
    const double top = rms.maxCoeff();
    for (int k = 0; k < n; ++k) largest_share[k] = std::max(largest_share[k], top > 0 ? rms[k] / top : 0.0);
  }
  std::vector<int> joints;
  std::vector<std::string> silent;
  for (int k = 0; k < n; ++k) {
    if (largest_share[k] >= kNoTorqueRatio) {
      joints.push_back(k);
    } else {
      silent.push_back(model.joints[static_cast<std::size_t>(k)].name + " (tau" + std::to_string(k + 1) + ")");
    }
  }
  if (joints.empty()) throw InputError("tau", "every torque column is zero: identification needs measured torques");
  if (!silent.empty()) {
    warnings.push_back("the torque of " + join_words(silent) + " is zero throughout (below 1e-4 of the largest joint's): taken as "
                       "not measured, so its rows are left out of the fit and the judge; give torque_joints "
                       "(--torque-joints) to say which joints have torque sensors");
  }
  return joints;
}

/// Step 1: the runs against the URDF's limits — a position beyond a joint's range (by more than 1 % of it
/// and 0.01), a speed above its velocity limit by 10 % — named joint by joint, with the likely cause: angles
/// logged in degrees (they would fit once converted: one warning for all such joints) or a log of another arm.
std::vector<std::string> limit_warnings(const Model& model, const Runs& runs) {
  std::vector<std::string> warnings;
  std::vector<std::string> in_degrees;  // "q1 (name) reaches -70.5 rad against -2.9 rad"
  const int n = model.joint_count();
  for (int k = 0; k < n; ++k) {
    const Joint& joint = model.joints[static_cast<std::size_t>(k)];
    double low = std::numeric_limits<double>::infinity(), high = -low, fastest = 0.0;
    for (const Trajectory& run : runs) {
      const auto q = run.q.col(k);
      low = std::min(low, q.minCoeff());
      high = std::max(high, q.maxCoeff());
      // Speeds over ±5 samples: the noise of single steps stays small against any limit.
      const Eigen::Index span = 5;
      for (Eigen::Index s = span; s + span < q.size(); ++s) {
        fastest = std::max(fastest, std::abs(q[s + span] - q[s - span]) / (run.t[s + span] - run.t[s - span]));
      }
    }
    const JointLimits& limits = joint.limits;
    const char* unit = joint.type == JointType::prismatic ? "m" : "rad";
    std::ostringstream text;
    text.precision(3);
    // lower == upper: the URDF parser has already said the joint has no range.
    if (std::isfinite(limits.lower) && std::isfinite(limits.upper) && limits.lower < limits.upper) {
      const double margin = 0.01 * (limits.upper - limits.lower) + 0.01;
      if (low < limits.lower - margin || high > limits.upper + margin) {
        const bool below = low < limits.lower - margin;
        text << "q" << k + 1 << " (" << joint.name << ") reaches " << (below ? low : high) << " " << unit;
        const double to_radians = std::numbers::pi / 180.0;
        // Degrees when no arm could have moved so in radians (wider than the joint's range, or beyond a turn)
        // and the converted angles fit.
        const bool impossible = high - low > limits.upper - limits.lower || std::max(-low, high) > 2 * std::numbers::pi;
        if (joint.type != JointType::prismatic && impossible && low * to_radians >= limits.lower - margin &&
            high * to_radians <= limits.upper + margin) {
          text << " against " << (below ? limits.lower : limits.upper);
          in_degrees.push_back(text.str());
        } else {
          text << ", beyond the URDF's limit " << (below ? limits.lower : limits.upper) << " " << unit
               << ": is this the log of this arm, with its joints in the URDF's order?";
          warnings.push_back(text.str());
        }
        continue;
      }
    }
    // A velocity limit of 0 is urdfdom's value for a missing attribute, not a limit.
    if (std::isfinite(limits.velocity) && limits.velocity > 0.0 && fastest > 1.1 * limits.velocity) {
      text << "q" << k + 1 << " (" << joint.name << ") moves at up to " << fastest << " " << unit << "/s, above the URDF's "
           << "velocity limit " << limits.velocity << " " << unit << "/s: check the units of q and t";
      warnings.push_back(text.str());
    }
  }
  if (!in_degrees.empty()) {
    std::string text = "the angles look like degrees: ";
    for (std::size_t i = 0; i < in_degrees.size(); ++i) text += (i > 0 ? ", " : "") + in_degrees[i];
    text += " (the URDF's limit); converted from degrees they lie within the limits: give the angle unit "
            "(--angle-unit deg, angle_unit=deg in the API)";
    warnings.insert(warnings.begin(), text);
  }
  return warnings;
}

/// Step 6: link masses the data see only in combinations that the physical fit moved far (by half or more)
/// from the URDF's, named with both values — so the report says what the written URDF holds.
std::string masses_moved(const Model& model, const IdentificationResult& result) {
  std::string list;
  const std::vector<LinkRow> links = link_table(model, result);
  for (std::size_t k = 0; k < links.size(); ++k) {
    const double before = result.prior[static_cast<Eigen::Index>(10 * k)], after = links[k].mass;
    if (links[k].mass_determined() || !(std::abs(after - before) > 0.5 * std::abs(before))) continue;
    list += (list.empty() ? "" : ", ") + links[k].link + " " + manipid::detail::short_number(before) + " -> " +
            manipid::detail::short_number(after) + " kg";
  }
  if (list.empty()) return {};
  return "the physical fit moved link masses the data see only in sums with other parameters far from the URDF's values (" +
         list + "): the real bodies nearest the URDF's values (in the scaled distance of the fit's prior term) that keep what "
         "the data determine; the link table and a written URDF hold these";
}

/// One friction model tried by step 3.
struct FrictionCandidate {
  ParameterLayout layout;
  BaseParameters base;
  std::vector<int> columns;  ///< the base's independent parameters as indices of the full layout
  Eigen::VectorXd beta_prior;
};

FrictionCandidate friction_candidate(const Model& model, const ParameterLayout& layout, const ParameterLayout& full,
                                     const Eigen::VectorXd& prior_full, const BaseParameterOptions& options) {
  const int n = model.joint_count();
  FrictionCandidate candidate;
  candidate.layout = layout;
  candidate.base = base_parameters(model, layout, options);
  const std::vector<int> map = layout_map(layout, full, n);
  Eigen::VectorXd prior(layout.size(n));
  for (int i = 0; i < layout.size(n); ++i) prior[i] = prior_full[map[static_cast<std::size_t>(i)]];
  candidate.beta_prior = candidate.base.combination * prior;
  for (int index : candidate.base.independent) candidate.columns.push_back(map[static_cast<std::size_t>(index)]);
  return candidate;
}

/// W's columns `columns`.
Eigen::MatrixXd select_columns(const Eigen::MatrixXd& W, const std::vector<int>& columns) {
  Eigen::MatrixXd selected(W.rows(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t i = 0; i < columns.size(); ++i) selected.col(static_cast<Eigen::Index>(i)) = W.col(columns[i]);
  return selected;
}

/// A candidate's held-out score with the base columns of `friction`: its rows' sums over every base
/// parameter of the full layout's base (so that the target's sums serve every friction model).
estimation::CrossValidation score(const estimation::BinnedSums& training, const estimation::BinnedSums& target,
                                  const estimation::TimeBins& bins, double guard, const FrictionCandidate& friction,
                                  const FrictionCandidate& full, const std::vector<double>& ridges) {
  // The sums are over the full base's columns; a friction model uses those of its own base that the full base
  // has (its friction columns are a subset). The terms it lacks are zero, as in the model it stands for.
  std::vector<int> positions;
  for (int column : friction.columns) {
    const auto at = std::find(full.columns.begin(), full.columns.end(), column);
    if (at != full.columns.end()) positions.push_back(static_cast<int>(at - full.columns.begin()));
  }
  Eigen::VectorXd prior = Eigen::VectorXd::Zero(full.beta_prior.size());
  for (int position : positions) prior[position] = full.beta_prior[position];
  return estimation::cross_validate(training, target, bins, guard, positions, prior, ridges);
}

}  // namespace

std::string friction_text(const ParameterLayout& layout) {
  std::vector<std::string> terms;
  if (layout.viscous) terms.emplace_back("viscous");
  if (layout.coulomb) terms.emplace_back("coulomb");
  if (layout.offset) terms.emplace_back("offset");
  std::string text;
  for (const std::string& term : terms) text += (text.empty() ? "" : ",") + term;
  return text.empty() ? "none" : text;
}

ParameterStructure parameter_structure(const Model& model, const ParameterLayout& layout) {
  const int n = model.joint_count();
  ParameterStructure structure;
  structure.parameter_count = layout.size(n);
  structure.parameter_names = standard_parameter_names(n, layout);
  for (int k = 0; k < n; ++k) {
    structure.link_offsets.push_back(kInertialParametersPerBody * k);
    structure.link_names.push_back(model.joints[static_cast<std::size_t>(k)].link);
    for (int begin : {layout.viscous_begin(n), layout.coulomb_begin(n), layout.armature_begin(n)}) {
      if (begin >= 0) structure.non_negative.push_back(begin + k);
    }
  }
  std::sort(structure.non_negative.begin(), structure.non_negative.end());
  return structure;
}

IdentificationResult identify(const Model& model, const Trajectory& data, const IdentificationOptions& options) {
  return identify(model, std::vector<Trajectory>{data}, options);
}

namespace {

IdentificationResult identify_runs(const Model& model, const std::vector<Trajectory>& measured,
                                   const IdentificationOptions& options) {
  const auto started = Clock::now();
  const int n = model.joint_count();
  IdentificationResult result;
  result.judge = options.judge;
  result.runs = static_cast<int>(measured.size());
  if (measured.empty()) throw InputError("dataset_ids", "identification needs at least one run");

  // The full layout: every friction term a candidate may use.
  ParameterLayout full_layout = options.layout;
  if (options.friction_auto) full_layout.viscous = full_layout.coulomb = full_layout.offset = true;
  const int p = full_layout.size(n);
  const Eigen::VectorXd prior = options.prior.size() ? options.prior : standard_parameters(model, full_layout);
  if (prior.size() != p) {
    throw InputError("prior", "the prior has " + std::to_string(prior.size()) + " entries, the robot's standard "
                                  "vector " + std::to_string(p));
  }
  if (!prior.allFinite()) throw InputError("prior", "the prior holds a value that is not a finite number");
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const std::string which = measured.size() > 1 ? "run " + std::to_string(i + 1) + ": " : "";
    if (measured[i].joint_count() != n) {
      throw InputError("q", which + "the data has " + std::to_string(measured[i].joint_count()) + " joints, the robot (" +
                                model.name + ") has " + std::to_string(n));
    }
    if (!measured[i].has_torque()) {
      throw InputError("tau", which + "the data has no tau columns: identification needs measured torques");
    }
  }
  if ((options.half_length > 0) != (options.band > 0.0)) {
    throw InputError(options.band > 0.0 ? "half_length" : "band",
                     "give the differentiation filter's half_length and band together, or neither (chosen by rule)");
  }
  if (!(options.comparison_cutoff_hz >= 0.0) || !std::isfinite(options.comparison_cutoff_hz)) {
    throw InputError("comparison_cutoff", "the comparison cut-off must be a positive number of Hz (or 0: chosen)");
  }
  if (!std::isfinite(options.ridge)) throw InputError("ridge", "the ridge must be a number >= 0 (or < 0: chosen)");
  if (options.weighting == JointWeighting::inverse_variance) {
    throw InputError("weights", "a URDF robot's joints are weighted unit or per-joint (each by its residual's variance)");
  }

  // Step 1.
  std::vector<std::optional<Trajectory>> storage;
  const Runs runs = prepare_runs(measured, options.preparation, storage, result.warnings);
  const double dt = runs.front().get().dt();
  for (const Trajectory& run : runs) options.judge.validate(dt, run.t[run.samples() - 1] - run.t[0]);
  result.torque_joints = measured_joints(model, runs, options.torque_joints, result.warnings);
  for (std::string& warning : limit_warnings(model, runs)) result.warnings.push_back(std::move(warning));
  const std::vector<int>& joints = result.torque_joints;

  // Step 2: the candidates' cut-offs, D for the highest of them (and the judge's), the regressor signals.
  const std::vector<double> cutoffs = candidate_cutoffs(options.comparison_cutoff_hz, options.judge.cutoff_hz, dt);
  const double highest = std::max(*std::max_element(cutoffs.begin(), cutoffs.end()), options.judge.cutoff_hz);
  FilterPair filters = differentiation_for(highest, dt, options.judge.trim_seconds);
  if (options.half_length > 0) {
    filters.differentiation = FilterSettings{options.half_length, options.band, dt};
    filters.working_step = working_step(filters.differentiation);
  }
  std::vector<RegressorSignals> signals;
  for (const Trajectory& run : runs) {
    signals.push_back(regressor_signals(model, full_layout, run, filters, options.cancel));
    if (signals.back().t.size() == 0) {
      result.cancelled = true;
      result.wall_seconds = std::chrono::duration<double>(Clock::now() - started).count();
      return result;
    }
  }
  // Only the full layout's base columns are filtered, in the base's order: every friction model's base is
  // among them, and the other columns are combinations of them (W = W_b C).
  std::vector<int> base_columns;
  const auto rows_at = [&](double cutoff) {
    std::vector<FilteredRows> per_run;
    for (const RegressorSignals& run : signals) {
      per_run.push_back(filtered_rows(run, p, cutoff, filters.trim_seconds, joints, base_columns));
    }
    return stack(std::move(per_run));
  };

  // Step 3: the friction models and the candidates.
  std::vector<FrictionCandidate> frictions;
  BaseParameterOptions base_options = options.base;
  base_options.cancel = options.cancel;
  frictions.push_back(friction_candidate(model, full_layout, full_layout, prior, base_options));
  if (options.friction_auto) {
    for (const auto& [viscous, coulomb] : {std::pair{false, false}, {true, false}, {true, true}}) {
      ParameterLayout layout = full_layout;
      layout.viscous = viscous;
      layout.coulomb = coulomb;
      layout.offset = false;
      frictions.push_back(friction_candidate(model, layout, full_layout, prior, base_options));
    }
  }
  const FrictionCandidate& full = frictions.front();
  base_columns = full.columns;
  const std::vector<double> ridges = options.ridge >= 0 ? std::vector<double>{options.ridge} : estimation::default_ridges();
  const bool choosing = cutoffs.size() > 1 || ridges.size() > 1 || frictions.size() > 1;

  // Each candidate's rows are reduced to their sums by time bin as soon as they are made; only the best
  // candidate's rows are kept (a run's rows for seven candidates would be most of the job's memory).
  std::size_t chosen_cutoff = 0, chosen_friction = 0;
  double chosen_ridge = ridges.front();
  StackedRows chosen_rows;
  result.held_out_error = std::numeric_limits<double>::quiet_NaN();
  if (!choosing) {
    chosen_rows = rows_at(cutoffs.front());
  } else {
    const StackedRows target = rows_at(options.judge.cutoff_hz);
    const estimation::TimeBins bins(estimation::run_spans(target.run_of_row, target.time_of_row, static_cast<int>(runs.size())),
                                    kHeldOutFolds, kHeldOutBinsPerFold);
    const estimation::BinnedSums target_sums =
        estimation::bin_rows(target.W, target.tau, estimation::bins_of_rows(bins, target.run_of_row, target.time_of_row), bins.count());
    const auto guard_for = [&](double cutoff) { return held_out_guard(cutoff, options.judge.cutoff_hz, filters); };
    // The cut-off with the full friction model, then (with friction_auto) the friction models at that cut-off.
    double best = std::numeric_limits<double>::infinity();
    estimation::BinnedSums chosen_sums;
    for (std::size_t c = 0; c < cutoffs.size(); ++c) {
      checkpoint(options.cancel, "the filter choice");
      StackedRows rows = cutoffs[c] == options.judge.cutoff_hz ? target : rows_at(cutoffs[c]);
      estimation::BinnedSums sums =
          estimation::bin_rows(rows.W, rows.tau, estimation::bins_of_rows(bins, rows.run_of_row, rows.time_of_row), bins.count());
      const estimation::CrossValidation cv = score(sums, target_sums, bins, guard_for(cutoffs[c]), full, full, ridges);
      result.candidates.push_back({cutoffs[c], friction_text(full.layout), cv.ridges[static_cast<std::size_t>(cv.best)],
                                   cv.best_relative_error()});
      if (cv.best_relative_error() < best) {
        best = cv.best_relative_error();
        chosen_cutoff = c;
        chosen_ridge = cv.ridges[static_cast<std::size_t>(cv.best)];
        chosen_rows = std::move(rows);
        chosen_sums = std::move(sums);
      }
    }
    for (std::size_t f = 1; f < frictions.size(); ++f) {
      checkpoint(options.cancel, "the friction choice");
      const estimation::CrossValidation cv =
          score(chosen_sums, target_sums, bins, guard_for(cutoffs[chosen_cutoff]), frictions[f], full, ridges);
      result.candidates.push_back({cutoffs[chosen_cutoff], friction_text(frictions[f].layout),
                                   cv.ridges[static_cast<std::size_t>(cv.best)], cv.best_relative_error()});
      if (cv.best_relative_error() < best) {
        best = cv.best_relative_error();
        chosen_friction = f;
        chosen_ridge = cv.ridges[static_cast<std::size_t>(cv.best)];
      }
    }
    result.held_out_error = best;
    result.chosen_by_held_out = true;
  }

  // Step 4: the chosen candidate's rows over its own layout.
  const FrictionCandidate& friction = frictions[chosen_friction];
  const StackedRows& rows = chosen_rows;
  result.layout = friction.layout;
  result.ridge = chosen_ridge;
  filters.comparison_cutoff_hz = cutoffs[chosen_cutoff];
  result.filters = filters;
  result.base = friction.base;
  const BaseParameters& base = result.base;
  const int b = base.size();
  result.standard_names = standard_parameter_names(n, result.layout);
  const std::vector<int> map = layout_map(result.layout, full_layout, n);
  result.prior.resize(result.layout.size(n));
  for (int i = 0; i < result.layout.size(n); ++i) result.prior[i] = prior[map[static_cast<std::size_t>(i)]];
  for (int index : base.absent) result.unidentifiable.push_back(result.standard_names[static_cast<std::size_t>(index)]);
  result.rows = static_cast<int>(rows.W.rows());
  // The chosen friction model's base columns among the full base's (its friction columns are a subset).
  std::vector<int> positions;
  for (int column : friction.columns) {
    positions.push_back(static_cast<int>(std::find(full.columns.begin(), full.columns.end(), column) - full.columns.begin()));
  }
  const Eigen::MatrixXd W_b = select_columns(rows.W, positions);
  const Eigen::VectorXd& beta_prior = friction.beta_prior;
  const Eigen::Index J = static_cast<Eigen::Index>(joints.size());

  estimation::LinearSolveOptions solve_options;
  solve_options.prior = beta_prior;
  solve_options.ridge = chosen_ridge;
  result.joint_weights = Eigen::VectorXd::Ones(J);
  estimation::LinearSolution solution = estimation::solve_linear(W_b, rows.tau, solve_options);
  if (options.weighting == JointWeighting::per_joint) {
    result.joint_weights = estimation::per_joint_weights(solution.residual, J);
    const Eigen::VectorXd weights = estimation::row_weights(result.joint_weights, W_b.rows());
    solution = estimation::solve_linear(weights.asDiagonal() * W_b, weights.asDiagonal() * rows.tau, solve_options);
    solution.residual = rows.tau - W_b * solution.estimate;
  }
  result.estimate = solution.estimate;

  // Step 5.
  const Eigen::VectorXd& residual = solution.residual;
  result.residual_rms = estimation::joint_residual_rms(residual, J);
  const double dof = std::max(1.0, static_cast<double>(residual.size() - solution.determined));
  result.residual_variance = residual.squaredNorm() / dof;
  const Eigen::VectorXd weighted = estimation::row_weights(result.joint_weights, residual.size()).cwiseProduct(residual);
  const double weighted_variance =
      weighted.squaredNorm() / dof * estimation::filtered_residual_factor(rows.row_step, rows.lowpass_energy);
  const Eigen::MatrixXd covariance = weighted_variance * solution.covariance_unit;
  result.data_share = solution.parameter_share;
  result.std_errors = covariance.diagonal().cwiseSqrt();
  result.correlation = Eigen::MatrixXd::Constant(b, b, std::numeric_limits<double>::quiet_NaN());
  std::vector<std::string> barely;
  for (int i = 0; i < b; ++i) {
    if (!(result.data_share[i] > 0.0)) result.std_errors[i] = std::numeric_limits<double>::quiet_NaN();
    if (result.data_share[i] < kBarelySeenShare) {
      result.unexcited.push_back(base.names[static_cast<std::size_t>(i)]);
      barely.push_back(base.names[static_cast<std::size_t>(i)] + " (" + percent(result.data_share[i]) + ")");
    }
  }
  for (int i = 0; i < b; ++i) {
    for (int j = 0; j < b; ++j) {
      if (std::isnan(result.std_errors[i]) || std::isnan(result.std_errors[j]) || !(covariance(i, i) > 0) ||
          !(covariance(j, j) > 0)) {
        continue;
      }
      result.correlation(i, j) = covariance(i, j) / std::sqrt(covariance(i, i) * covariance(j, j));
    }
  }
  result.condition_number = solution.condition_number;
  if (!barely.empty()) {
    result.warnings.push_back("the data barely see " + join_words(barely) + " (each base parameter's data share: the part of "
                              "its estimate the data determine rather than the URDF): these stay near the URDF's values; "
                              "a richer excitation (manipid excitation) or another run would determine them");
  }
  // The standard vector with these base parameters nearest to the prior: π0 + Cᵀ(CCᵀ)⁻¹(β̂ − Cπ0).
  const Eigen::MatrixXd& C = base.combination;
  const Eigen::VectorXd correction = (C * C.transpose()).ldlt().solve(result.estimate - beta_prior);
  result.point = result.prior + C.transpose() * correction;

  // Step 6.
  const ParameterStructure structure = parameter_structure(model, result.layout);
  if (options.physical) {
    // The same rows and weights as the least squares, over every standard parameter of the chosen layout.
    ConsistentFitProblem problem;
    const Eigen::VectorXd weights = estimation::row_weights(result.joint_weights, rows.W.rows());
    problem.R = weights.asDiagonal() * (W_b * C);  // every standard column: W = W_b C for any motion
    problem.z = weights.asDiagonal() * rows.tau;
    problem.unconstrained = result.point;
    problem.prior = result.prior;
    ConsistentFitOptions fit_options;
    fit_options.cancel = options.cancel;
    // Weakly excited real arms (the KUKA log: condition 110) need a few hundred iterations from a very
    // inconsistent least-squares point; each costs O(p³) on the reduced problem, well under a millisecond.
    fit_options.max_iterations = 2000;
    result.physical = fit_consistent(structure, problem, fit_options);
    if (result.physical->termination == FitTermination::cancelled) {
      result.cancelled = true;
    } else {
      result.point = result.physical->estimate;
      result.estimate = C * result.point;
      result.residual_rms = estimation::joint_residual_rms(rows.tau - W_b * result.estimate, J);
      if (!result.physical->converged()) {
        result.warnings.push_back("the physically consistent fit did not converge: " + result.physical->message);
      }
      if (std::string moved = masses_moved(model, result); !moved.empty()) result.warnings.push_back(std::move(moved));
    }
  }
  result.consistency = check_consistency(structure, result.point);
  if (std::string far = far_from_prior(base, result.estimate, beta_prior, W_b, rows.tau); !far.empty()) {
    result.warnings.push_back(std::move(far));
  }
  std::vector<TorquePrediction> fits;
  for (const Trajectory& run : runs) {
    fits.push_back(predict_torque(model, result.layout, result.point, run, result.judge, result.torque_joints));
  }
  result.fit = combine(fits);
  result.wall_seconds = std::chrono::duration<double>(Clock::now() - started).count();
  return result;
}

}  // namespace

IdentificationResult identify(const Model& model, const std::vector<Trajectory>& measured, const IdentificationOptions& options) {
  const auto started = Clock::now();
  try {
    return identify_runs(model, measured, options);
  } catch (const Interrupted&) {
    // Inside a long step (the base parameters, a candidate's filtering): as a cancel between steps ends.
    IdentificationResult result;
    result.judge = options.judge;
    result.runs = static_cast<int>(measured.size());
    result.cancelled = true;
    result.wall_seconds = std::chrono::duration<double>(Clock::now() - started).count();
    return result;
  }
}

ValidationReport validate(const Model& model, const IdentificationResult& result, const std::vector<Trajectory>& runs,
                          const DataPreparation& preparation) {
  if (runs.empty()) throw InputError("validation_dataset_ids", "validation needs at least one run");
  ValidationReport report;
  std::vector<TorquePrediction> estimate, prior;
  DataPreparation same_grid = preparation;
  same_grid.uniform.dt = result.filters.differentiation.dt;  // the identification's period
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const Trajectory& data = runs[i];
    const std::string which = runs.size() > 1 ? "validation run " + std::to_string(i + 1) + ": " : "";
    if (data.joint_count() != model.joint_count()) {
      throw InputError("q", which + "the validation data has " + std::to_string(data.joint_count()) + " joints, the robot (" +
                                model.name + ") has " + std::to_string(model.joint_count()));
    }
    if (!data.has_torque()) {
      throw InputError("tau", which + "the validation data has no tau columns to compare the prediction with");
    }
    std::vector<std::string> warnings;
    std::optional<Trajectory> prepared;
    const Trajectory& uniform = prepare_data(data, same_grid, prepared, &warnings);
    for (const std::string& warning : warnings) report.warnings.push_back(which + warning);
    estimate.push_back(predict_torque(model, result.layout, result.point, uniform, result.judge, result.torque_joints));
    prior.push_back(predict_torque(model, result.layout, result.prior, uniform, result.judge, result.torque_joints));
  }
  report.estimate = combine(estimate);
  report.prior = combine(prior);
  return report;
}

}  // namespace manipid::robot

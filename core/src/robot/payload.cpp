// payload.cpp — a payload's inertial parameters from the torque an identified arm leaves unexplained (robot/payload.h).
#include "manipid/core/robot/payload.h"

#include "manipid/core/errors.h"
#include "manipid/core/estimation/cross_validation.h"
#include "manipid/core/estimation/joint_weighting.h"
#include "manipid/core/estimation/linear_least_squares.h"
#include "manipid/core/estimation/rules.h"
#include "manipid/core/robot/consistency.h"
#include "manipid/core/robot/consistent_fit.h"
#include "manipid/core/robot/filtered_regressor.h"
#include "numbers.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

namespace manipid::robot {
namespace {

using Vector10d = Eigen::Matrix<double, 10, 1>;
using Matrix10d = Eigen::Matrix<double, 10, 10>;
using manipid::detail::kNaN;
using estimation::JointWeighting;

/// A payload parameter whose data share is below this is not determined by the run (as an arm's base
/// parameter is barely seen below it: robot/identification.cpp).
constexpr double kDeterminedShare = 0.5;
/// A mass above this many standard errors is a payload; below, the run cannot tell it from none.
constexpr double kDetectedMass = 2.0;
/// A payload that leaves more than this share of the arm's residual explains little of it (a warning): a real
/// payload on the arm it was identified with leaves its noise (the simulated 3 kg tool: 0.3 %), a run of
/// another arm much more (links 2 and 3 half again as heavy: 36 %).
constexpr double kUnexplained = 0.25;
/// A negative mass says the arm's parameters do not describe the run only when what the arm leaves is material:
/// more than this share of the filtered torque. Below it (a noise-free run without payload leaves the filters'
/// rounding, 1e-6 of the torque, and a mass of −3.5 ± 1.2 mg), the answer is "no payload".
constexpr double kMaterialResidual = 1e-3;
/// The jackknife's blocks of time (jackknife_inflation).
constexpr int kJackknifeBlocks = 10;

/// What a parameter needs to be seen, for the warning naming it.
std::string what_excites(int index) {
  if (index == 0) return "vertical accelerations, or the arm held in several poses (gravity)";
  if (index <= 3) return "poses that turn the tip link relative to gravity";
  return "rotations of the tip link about several axes (the wrist joints moved fast, alone and together)";
}

/// The symmetric tensor of entries (xx, xy, xz, yy, yz, zz).
Eigen::Matrix3d tensor(const double* e) {
  Eigen::Matrix3d I;
  I << e[0], e[1], e[2], e[1], e[3], e[4], e[2], e[4], e[5];
  return I;
}

/// (m, c, I_c entries) from π_P = (m, h, I_O entries): c = h/m, I_c = I_O − (‖h‖² E − h hᵀ)/m.
Eigen::Matrix<double, 10, 1> mounted(const Vector10d& pi) {
  const double m = pi[0];
  const Eigen::Vector3d h = pi.segment<3>(1);
  const Eigen::Matrix3d Ic = tensor(pi.data() + 4) - (h.squaredNorm() * Eigen::Matrix3d::Identity() - h * h.transpose()) / m;
  Eigen::Matrix<double, 10, 1> out;
  out << m, h / m, Ic(0, 0), Ic(0, 1), Ic(0, 2), Ic(1, 1), Ic(1, 2), Ic(2, 2);
  return out;
}

/// ∂ mounted / ∂ π_P, analytic: c = h/m gives ∂c/∂m = −h/m², ∂c/∂h = E/m; I_c = I_O − S(h)/m with
/// S(h) = ‖h‖² E − h hᵀ gives ∂I_c/∂m = S(h)/m², ∂I_c/∂h_i = −(2 h_i E − e_i hᵀ − h e_iᵀ)/m, ∂I_c/∂I_O = identity.
Matrix10d mounted_jacobian(const Vector10d& pi) {
  const double m = pi[0];
  const Eigen::Vector3d h = pi.segment<3>(1);
  const auto entries = [](const Eigen::Matrix3d& A) {
    Eigen::Matrix<double, 6, 1> e;
    e << A(0, 0), A(0, 1), A(0, 2), A(1, 1), A(1, 2), A(2, 2);
    return e;
  };
  const Eigen::Matrix3d S = h.squaredNorm() * Eigen::Matrix3d::Identity() - h * h.transpose();
  Matrix10d J = Matrix10d::Zero();
  J(0, 0) = 1.0;
  J.block<3, 1>(1, 0) = -h / (m * m);
  J.block<3, 3>(1, 1) = Eigen::Matrix3d::Identity() / m;
  J.block<6, 1>(4, 0) = entries(S) / (m * m);
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(i);
    const Eigen::Matrix3d dS = 2.0 * h[i] * Eigen::Matrix3d::Identity() - e * h.transpose() - h * e.transpose();
    J.block<6, 1>(4, 1 + i) = -entries(dS) / m;
  }
  J.block<6, 6>(4, 4).setIdentity();
  return J;
}

/// The unknowns of step 3 and how π_P follows from them: π_P = G x + g0.
struct Unknowns {
  Eigen::MatrixXd G;                     // 10 × k
  Vector10d g0 = Vector10d::Zero();
  std::vector<int> parameter;            // x_i is π_P's parameter[i] (for names and shares)
};

Unknowns unknowns(const PayloadOptions& options) {
  Unknowns u;
  const bool mass = options.known_mass.has_value(), centre = options.known_centre_of_mass.has_value();
  std::vector<Eigen::Matrix<double, 10, 1>> columns;
  if (!mass) {
    Vector10d column = Vector10d::Unit(0);
    if (centre) column.segment<3>(1) = *options.known_centre_of_mass;  // h = m c
    columns.push_back(column);
    u.parameter.push_back(0);
  } else {
    u.g0[0] = *options.known_mass;
    if (centre) u.g0.segment<3>(1) = *options.known_mass * *options.known_centre_of_mass;
  }
  if (!centre) {
    for (int i = 1; i <= 3; ++i) {
      columns.push_back(Vector10d::Unit(i));
      u.parameter.push_back(i);
    }
  }
  for (int i = 4; i < 10; ++i) {
    columns.push_back(Vector10d::Unit(i));
    u.parameter.push_back(i);
  }
  u.G.resize(10, static_cast<Eigen::Index>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c) u.G.col(static_cast<Eigen::Index>(c)) = columns[c];
  return u;
}

/// A candidate's rows: body n's columns in the tip link's frame (W_tip) and the arm's residual through L, the
/// unknowns' rows (A x ≈ y), and where each row lies in time (for the held-out folds).
struct PayloadRows {
  Eigen::MatrixXd W_tip, A;
  Eigen::VectorXd residual, y;
  std::vector<int> run_of_row;
  std::vector<double> time_of_row;
  int row_step = 1;
  double lowpass_energy = 1.0;

  std::vector<int> bins(const estimation::TimeBins& bins) const { return estimation::bins_of_rows(bins, run_of_row, time_of_row); }
};

PayloadRows payload_rows(const std::vector<RegressorSignals>& signals, int p, double cutoff, double trim_seconds,
                         const std::vector<int>& joints, const std::vector<int>& body_columns, const Matrix10d& T,
                         const Unknowns& u) {
  std::vector<FilteredRows> per_run;
  Eigen::Index total = 0;
  for (const RegressorSignals& run : signals) {
    per_run.push_back(filtered_rows(run, p, cutoff, trim_seconds, joints, body_columns));
    total += per_run.back().W.rows();
  }
  PayloadRows rows;
  Eigen::MatrixXd W(total, kInertialParametersPerBody);
  rows.residual.resize(total);
  Eigen::Index at = 0;
  const Eigen::Index J = static_cast<Eigen::Index>(joints.size());
  for (std::size_t run = 0; run < per_run.size(); ++run) {
    const FilteredRows& part = per_run[run];
    W.middleRows(at, part.W.rows()) = part.W;
    rows.residual.segment(at, part.tau.size()) = part.tau;
    for (Eigen::Index r = 0; r < part.W.rows(); ++r) {
      rows.run_of_row.push_back(static_cast<int>(run));
      rows.time_of_row.push_back(part.t[r / J]);
    }
    at += part.W.rows();
    rows.row_step = part.row_step;
    rows.lowpass_energy = part.lowpass_energy;
  }
  rows.W_tip = W * T;  // columns for π_P
  rows.A = rows.W_tip * u.G;
  rows.y = rows.residual - rows.W_tip * u.g0;
  return rows;
}

/// How much larger the estimate's variance is than the white-residual formula says: the median, over the
/// determined unknowns, of a delete-one-block jackknife's variance (kJackknifeBlocks contiguous spans of
/// instants) over the formula's, at least 1. A real arm's residual is mostly what its model lacks, correlated
/// over seconds, not the white noise the formula assumes (the KUKA's run without a tool: 11 ± 3.7 g by the
/// formula, ± 8.4 g with the jackknife's inflation, 5.3); on simulated white noise the two agree.
double jackknife_inflation(const Eigen::MatrixXd& A, const Eigen::VectorXd& y, const estimation::LinearSolution& full,
                           double residual_variance, Eigen::Index joints) {
  const Eigen::Index instants = A.rows() / std::max<Eigen::Index>(joints, 1);
  if (instants < 4 * kJackknifeBlocks) return 1.0;
  const Eigen::Index k = A.cols();
  std::vector<Eigen::VectorXd> estimates;
  for (int b = 0; b < kJackknifeBlocks; ++b) {
    const Eigen::Index first = instants * b / kJackknifeBlocks * joints, last = instants * (b + 1) / kJackknifeBlocks * joints;
    Eigen::MatrixXd A_b(A.rows() - (last - first), k);
    Eigen::VectorXd y_b(A_b.rows());
    A_b << A.topRows(first), A.bottomRows(A.rows() - last);
    y_b << y.head(first), y.tail(y.size() - last);
    estimates.push_back(estimation::solve_linear(A_b, y_b).estimate);
  }
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(k);
  for (const Eigen::VectorXd& e : estimates) mean += e / kJackknifeBlocks;
  std::vector<double> ratios;
  for (Eigen::Index i = 0; i < k; ++i) {
    const double formula = residual_variance * full.covariance_unit(i, i);
    if (!(full.parameter_share[i] >= kDeterminedShare) || !(formula > 0.0)) continue;
    double spread = 0.0;
    for (const Eigen::VectorXd& e : estimates) spread += (e[i] - mean[i]) * (e[i] - mean[i]);
    ratios.push_back(spread * (kJackknifeBlocks - 1.0) / kJackknifeBlocks / formula);
  }
  if (ratios.empty()) return 1.0;
  std::nth_element(ratios.begin(), ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2), ratios.end());
  return std::max(1.0, ratios[ratios.size() / 2]);
}

/// The rows that hold a given value in the physical fit outweigh the data's strongest direction (in the fit's
/// scaled coordinates) by this factor: the value holds to about 1/kHoldWeight² of the data's pull (1e-6), and
/// the normal equations stay well within double precision (their condition grows by kHoldWeight²).
constexpr double kHoldWeight = 1e3;

/// Step 5: the least-squares fit of L r ≈ W_tip π_P over real rigid bodies (robot/consistent_fit.h, one link).
/// The prior — what the directions the run does not excite keep — is the least-squares payload made a real
/// body (project_link: unchanged when it is one). A known mass or centre of mass (h = m c) enters as rows that
/// outweigh the data kHoldWeight-fold; the prior term's weight is scaled down by the same factor² so that it
/// weighs against the data as in an arm's fit (consistent_fit.h: ε relative to σ_max², here the data's).
ConsistentFitSummary physical_fit(const Eigen::MatrixXd& W_tip, const Eigen::VectorXd& residual, const Vector10d& least_squares,
                                  const PayloadOptions& options) {
  const Vector10d prior = project_link(least_squares, {}, "payload").link;
  const double m = prior[0];
  const double length = std::sqrt((prior[4] + prior[7] + prior[9]) / (2.0 * m));  // radius of gyration about O
  Vector10d scale;
  scale << m, Eigen::Vector3d::Constant(m * length), Eigen::Matrix<double, 6, 1>::Constant(m * length * length);
  const Matrix10d scaled_gram = scale.asDiagonal() * (W_tip.transpose() * W_tip) * scale.asDiagonal();
  const double sigma_data = std::sqrt(Eigen::SelfAdjointEigenSolver<Matrix10d>(scaled_gram, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff());

  std::vector<Vector10d> rows;
  std::vector<double> targets;
  if (options.known_mass) {  // m = m₀
    rows.push_back(Vector10d::Unit(0) * (kHoldWeight * sigma_data / scale[0]));
    targets.push_back(rows.back()[0] * *options.known_mass);
  }
  if (options.known_centre_of_mass) {  // h_i − c_i m = 0
    for (int i = 0; i < 3; ++i) {
      Vector10d row = Vector10d::Unit(1 + i);
      row[0] = -(*options.known_centre_of_mass)[i];
      rows.push_back(row * (kHoldWeight * sigma_data / scale[1 + i]));
      targets.push_back(0.0);
    }
  }
  ConsistentFitProblem problem;
  problem.R.resize(W_tip.rows() + static_cast<Eigen::Index>(rows.size()), 10);
  problem.z.resize(problem.R.rows());
  problem.R.topRows(W_tip.rows()) = W_tip;
  problem.z.head(W_tip.rows()) = residual;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    problem.R.row(W_tip.rows() + static_cast<Eigen::Index>(i)) = rows[i].transpose();
    problem.z[W_tip.rows() + static_cast<Eigen::Index>(i)] = targets[i];
  }
  problem.unconstrained = least_squares;
  problem.prior = prior;

  ParameterStructure structure;
  structure.parameter_count = 10;
  structure.link_offsets = {0};
  structure.link_names = {"payload"};
  for (const char* name : PayloadResult::names()) structure.parameter_names.emplace_back(name);
  ConsistentFitOptions fit;
  fit.parameter_scale = scale;
  if (!rows.empty()) fit.regularization /= kHoldWeight * kHoldWeight;
  fit.cancel = options.cancel;
  return fit_consistent(structure, problem, fit);
}

void check_input(const Model& model, const ArmParameters& arm, const std::vector<Trajectory>& runs,
                 const PayloadOptions& options) {
  const int n = model.joint_count();
  if (runs.empty()) throw InputError("dataset_ids", "a payload identification needs at least one run with the payload");
  if (arm.pi.size() != arm.layout.size(n)) {
    throw InputError("arm", "the arm's parameters have " + std::to_string(arm.pi.size()) + " entries, the robot's standard "
                            "vector with these friction terms " + std::to_string(arm.layout.size(n)));
  }
  if (!arm.pi.allFinite()) throw InputError("arm", "the arm's parameters hold a value that is not a finite number");
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const std::string which = runs.size() > 1 ? "run " + std::to_string(i + 1) + ": " : "";
    if (runs[i].joint_count() != n) {
      throw InputError("q", which + "the data has " + std::to_string(runs[i].joint_count()) + " joints, the robot (" +
                                model.name + ") has " + std::to_string(n));
    }
    if (!runs[i].has_torque()) throw InputError("tau", which + "the data has no tau columns: a payload is identified from torques");
  }
  if (options.known_mass && !(std::isfinite(*options.known_mass) && *options.known_mass > 0.0)) {
    throw InputError("known_mass", "a known payload mass must be a positive number of kg, got " +
                                       manipid::detail::short_number(*options.known_mass));
  }
  if (options.known_centre_of_mass && !options.known_centre_of_mass->allFinite()) {
    throw InputError("known_centre_of_mass", "a known centre of mass must be three finite numbers (m, tip-link frame)");
  }
  if (!(options.comparison_cutoff_hz >= 0.0) || !std::isfinite(options.comparison_cutoff_hz)) {
    throw InputError("comparison_cutoff", "the comparison cut-off must be a positive number of Hz (or 0: the judge's)");
  }
  if (options.weighting == JointWeighting::inverse_variance) {
    throw InputError("weights", "a payload's joints are weighted unit or per-joint (by each joint's residual), not by the "
                                "variance of their torque");
  }
  for (int joint : options.torque_joints) {
    if (joint < 0 || joint >= n) {
      throw InputError("torque_joints", "joint " + std::to_string(joint + 1) + " is not one of the robot's " + std::to_string(n));
    }
  }
}

}  // namespace

Matrix10d payload_to_last_body(const Model& model) {
  Matrix10d T;
  for (int i = 0; i < 10; ++i) {
    T.col(i) = InertialParameters::from_vector(Vector10d::Unit(i)).expressed_in(model.tip_placement).vector();
  }
  return T;
}

const std::array<const char*, 10>& PayloadResult::names() {
  static const std::array<const char*, 10> kNames = {"m", "mx", "my", "mz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"};
  return kNames;
}

Eigen::VectorXd with_payload(const Model& model, const ArmParameters& arm, const Eigen::Matrix<double, 10, 1>& payload) {
  const int n = model.joint_count();
  Eigen::VectorXd pi = arm.pi;
  pi.segment<10>(static_cast<Eigen::Index>(kInertialParametersPerBody) * (n - 1)) += payload_to_last_body(model) * payload;
  return pi;
}

PayloadResult identify_payload(const Model& model, const ArmParameters& arm, const std::vector<Trajectory>& measured,
                               const PayloadOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  check_input(model, arm, measured, options);
  const int n = model.joint_count();
  const int p = arm.layout.size(n);
  PayloadResult result;
  const auto finish = [&]() -> PayloadResult& {
    result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return result;
  };

  // Step 1.
  std::vector<std::optional<Trajectory>> storage;
  const PreparedRuns runs = prepare_runs(measured, options.preparation, storage, result.warnings);
  const double dt = runs.front().get().dt();
  for (const Trajectory& run : runs) options.judge.validate(dt, run.t[run.samples() - 1] - run.t[0]);
  if (options.torque_joints.empty()) {
    for (int k = 0; k < n; ++k) result.torque_joints.push_back(k);
  } else {
    result.torque_joints = options.torque_joints;
  }

  // Step 2: per run, the arm's torque taken from τ on the working grid, then L over the residual and body
  // n's columns (and, for the figures, over τ itself), at each candidate cut-off.
  const std::vector<double> cutoffs = candidate_cutoffs(options.comparison_cutoff_hz, options.judge.cutoff_hz, dt);
  const double highest = std::max(*std::max_element(cutoffs.begin(), cutoffs.end()), options.judge.cutoff_hz);
  const FilterPair filters = differentiation_for(highest, dt, options.judge.trim_seconds);
  std::vector<int> body_columns;
  for (int i = 0; i < kInertialParametersPerBody; ++i) body_columns.push_back(kInertialParametersPerBody * (n - 1) + i);
  std::vector<RegressorSignals> signals;
  std::vector<double> torque_energy(cutoffs.size(), 0.0);  // ‖L τ‖² per candidate, for the figures
  for (const Trajectory& run : runs) {
    RegressorSignals run_signals = regressor_signals(model, arm.layout, run, filters, options.cancel);
    if (run_signals.t.size() == 0) {
      result.cancelled = true;
      return finish();
    }
    for (std::size_t c = 0; c < cutoffs.size(); ++c) {
      torque_energy[c] +=
          filtered_rows(run_signals, p, cutoffs[c], filters.trim_seconds, result.torque_joints, {body_columns[0]}).tau.squaredNorm();
    }
    for (int k = 0; k < n; ++k) {
      const std::vector<int>& columns = run_signals.columns[static_cast<std::size_t>(k)];
      Eigen::VectorXd pi_k(static_cast<Eigen::Index>(columns.size()));
      for (std::size_t c = 0; c < columns.size(); ++c) pi_k[static_cast<Eigen::Index>(c)] = arm.pi[columns[c]];
      run_signals.tau.col(k) -= run_signals.Y[static_cast<std::size_t>(k)] * pi_k;
    }
    signals.push_back(std::move(run_signals));
  }
  const Unknowns u = unknowns(options);
  const Matrix10d T = payload_to_last_body(model);
  const auto rows_at = [&](double cutoff) { return payload_rows(signals, p, cutoff, filters.trim_seconds, result.torque_joints, body_columns, T, u); };

  // Step 3a (L's cut-off chosen by held-out evidence as an arm's identification chooses: robot/identification.h's step 3):
  // each candidate's fit on four fifths of every run predicts the fifth it did not see, against one target —
  // the arm's residual through the judge's low-pass.
  std::size_t chosen = 0;
  PayloadRows rows;
  result.held_out_error = kNaN;
  if (cutoffs.size() == 1) {
    rows = rows_at(cutoffs.front());
  } else {
    const PayloadRows target = rows_at(options.judge.cutoff_hz);
    const estimation::TimeBins bins(estimation::run_spans(target.run_of_row, target.time_of_row, static_cast<int>(runs.size())),
                                    kHeldOutFolds, kHeldOutBinsPerFold);
    const estimation::BinnedSums target_sums = estimation::bin_rows(target.A, target.y, target.bins(bins), bins.count());
    std::vector<int> columns(static_cast<std::size_t>(target.A.cols()));
    for (std::size_t i = 0; i < columns.size(); ++i) columns[i] = static_cast<int>(i);
    const Eigen::VectorXd prior = Eigen::VectorXd::Zero(target.A.cols());
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < cutoffs.size(); ++c) {
      if (options.cancel && options.cancel->load(std::memory_order_relaxed)) {
        result.cancelled = true;
        return finish();
      }
      PayloadRows candidate = cutoffs[c] == options.judge.cutoff_hz ? target : rows_at(cutoffs[c]);
      const estimation::CrossValidation cv =
          estimation::cross_validate(estimation::bin_rows(candidate.A, candidate.y, candidate.bins(bins), bins.count()),
                                     target_sums, bins, held_out_guard(cutoffs[c], options.judge.cutoff_hz, filters),
                                     columns, prior, {0.0});
      result.candidates.push_back({cutoffs[c], cv.best_relative_error()});
      if (cv.best_relative_error() < best) {
        best = cv.best_relative_error();
        chosen = c;
        rows = std::move(candidate);
      }
    }
    if (std::isfinite(best)) {
      result.held_out_error = best;
    } else {  // no figure to choose by (a residual of zero: nothing to predict): the first candidate
      result.candidates.clear();
      rows = rows_at(cutoffs.front());
    }
  }
  result.comparison_cutoff_hz = cutoffs[chosen];
  result.rows = static_cast<int>(rows.A.rows());
  const Eigen::MatrixXd& A = rows.A;
  const Eigen::VectorXd& y = rows.y;
  const int row_step = rows.row_step;
  const double lowpass_energy = rows.lowpass_energy;
  const Eigen::Index J = static_cast<Eigen::Index>(result.torque_joints.size());

  // Step 3b: the unknowns x, A x ≈ L r − W_tip g0 — with per_joint weighting, each joint's rows divided by
  // its residual RMS from a first, unweighted solve (as an arm's identification weighs them; the weighted
  // rows below are what the standard errors, the jackknife and the physical fit see).
  estimation::LinearSolution solution = estimation::solve_linear(A, y);
  result.joint_weights = Eigen::VectorXd::Ones(J);
  Eigen::MatrixXd A_weighted, W_tip_weighted;
  Eigen::VectorXd y_weighted, residual_weighted;
  const bool weighted = options.weighting == JointWeighting::per_joint;
  if (weighted) {
    result.joint_weights = estimation::per_joint_weights(solution.residual, J);
    const Eigen::VectorXd w = estimation::row_weights(result.joint_weights, A.rows());
    A_weighted = w.asDiagonal() * A;
    y_weighted = w.asDiagonal() * y;
    W_tip_weighted = w.asDiagonal() * rows.W_tip;
    residual_weighted = w.asDiagonal() * rows.residual;
    solution = estimation::solve_linear(A_weighted, y_weighted);
  }
  const Eigen::MatrixXd& A_fit = weighted ? A_weighted : A;
  const Eigen::VectorXd& y_fit = weighted ? y_weighted : y;
  const Eigen::MatrixXd& W_tip = weighted ? W_tip_weighted : rows.W_tip;
  const Eigen::VectorXd& residual = weighted ? residual_weighted : rows.residual;
  const double dof = std::max(1.0, static_cast<double>(y.size() - solution.determined));
  result.residual_variance =
      solution.residual.squaredNorm() / dof * estimation::filtered_residual_factor(row_step, lowpass_energy);
  const double inflation = jackknife_inflation(A_fit, y_fit, solution, result.residual_variance, J);
  result.variance_inflation = inflation;
  const Eigen::MatrixXd covariance_x = inflation * result.residual_variance * solution.covariance_unit;
  result.estimate = u.G * solution.estimate + u.g0;
  const Matrix10d covariance = u.G * covariance_x * u.G.transpose();
  result.std_errors = covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  result.data_share.setOnes();  // a value given is known
  for (std::size_t i = 0; i < u.parameter.size(); ++i) {
    const int index = u.parameter[i];
    const double share = solution.parameter_share[static_cast<Eigen::Index>(i)];
    result.data_share[index] = share;
    if (!(share > 0.0)) result.std_errors[index] = kNaN;
    if (share < kDeterminedShare) {
      result.undetermined.push_back(PayloadResult::names()[static_cast<std::size_t>(index)]);
      result.warnings.push_back("the run does not excite " + std::string(PayloadResult::names()[static_cast<std::size_t>(index)]) +
                                " (its data share " + manipid::detail::short_number(100.0 * share) + " %): it is not determined and "
                                "stays at 0" + (options.physical ? " (the physical fit: at the nearest value that keeps the "
                                                                   "payload a real body)" : "") +
                                "; " + what_excites(index) + " would determine it");
    }
  }
  const double torque_norm = std::sqrt(torque_energy[chosen]);
  result.arm_only_error = torque_norm > 0 ? rows.residual.norm() / torque_norm : kNaN;
  result.with_payload_error = torque_norm > 0 ? (y - A * solution.estimate).norm() / torque_norm : kNaN;

  // Step 4.
  result.mass = result.estimate[0];
  result.mass_std_error = result.std_errors[0];
  const bool mass_given = options.known_mass.has_value();
  result.detected = mass_given || (result.data_share[0] >= kDeterminedShare && result.mass > kDetectedMass * result.mass_std_error);
  const std::string mass_text =
      manipid::detail::short_number(result.mass) + " ± " + manipid::detail::short_number(result.mass_std_error) + " kg";
  if (!result.detected && result.data_share[0] >= kDeterminedShare && result.mass < -kDetectedMass * result.mass_std_error &&
      result.arm_only_error > kMaterialResidual) {
    // No body has a negative mass: what the arm leaves is not a payload's torque.
    result.warnings.push_back("the run's residual is not a payload's: its mass comes out negative, " + mass_text +
                              ", so the arm's parameters do not describe this run (another arm, a tool that was already "
                              "mounted when the arm was identified, or a changed set-up); the centre of mass and the inertia "
                              "are not reported");
  } else if (!result.detected) {
    result.warnings.push_back("no payload: the mass, " + mass_text + ", is not distinguishable from 0, so the "
                              "centre of mass and the inertia are not reported");
  }
  if (result.detected && result.with_payload_error > kUnexplained * result.arm_only_error) {
    result.warnings.push_back("the payload explains little of what the arm leaves (the run's torque error " +
                              manipid::detail::short_number(100.0 * result.arm_only_error) + " % with the arm alone, " +
                              manipid::detail::short_number(100.0 * result.with_payload_error) + " % with the payload): the "
                              "arm's parameters may not describe this run (another arm, a changed set-up), and the payload's "
                              "values absorb the mismatch");
  }
  if (!result.detected) {
    if (options.physical) result.warnings.push_back("no physical fit: there is no payload to make a real body of");
    result.inertia.fill(kNaN);
    result.inertia_std_errors.fill(kNaN);
    return finish();
  }

  // Step 5.
  if (options.physical) {
    PayloadResult::PhysicalFit physical;
    physical.least_squares_consistent = check_link(result.estimate, "the payload", &physical.least_squares_findings).consistent();
    if (!physical.least_squares_consistent) {
      const ConsistentFitSummary fit = physical_fit(W_tip, residual, result.estimate, options);
      if (fit.termination == FitTermination::cancelled) {
        result.cancelled = true;
        return finish();
      }
      const double before = (residual - W_tip * result.estimate).squaredNorm();
      const double after = (residual - W_tip * fit.estimate).squaredNorm();
      physical.relative_cost_increase = before > 0 ? std::max(0.0, after / before - 1.0) : 0.0;
      physical.report = fit.brief_report();
      result.estimate = fit.estimate;
      result.mass = result.estimate[0];
      result.with_payload_error = torque_norm > 0 ? (rows.residual - rows.W_tip * fit.estimate).norm() / torque_norm : kNaN;
    }
    result.physical = physical;
  }
  result.consistent = check_link(result.estimate, "the payload", &result.consistency_findings).consistent();
  if (!result.consistent && !options.physical) {
    std::string findings;
    for (const std::string& finding : result.consistency_findings) findings += (findings.empty() ? "" : "; ") + finding;
    result.warnings.push_back("the payload's least-squares values are not a real rigid body (" + findings +
                              "): the physical fit makes them one (--physical; \"physical\": true in a request)");
  }
  const Vector10d values = mounted(result.estimate);
  const Matrix10d jacobian = mounted_jacobian(result.estimate);
  const Vector10d errors = (jacobian * covariance * jacobian.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  result.centre_of_mass = values.segment<3>(1);
  result.centre_of_mass_std_errors = errors.segment<3>(1);
  if (options.known_centre_of_mass) {  // given: as it was given, exactly
    result.centre_of_mass = *options.known_centre_of_mass;
    result.centre_of_mass_std_errors.setZero();
  }
  for (int i = 0; i < 6; ++i) {
    result.inertia[static_cast<std::size_t>(i)] = values[4 + i];
    result.inertia_std_errors[static_cast<std::size_t>(i)] = errors[4 + i];
  }
  // A value derived from an undetermined one is not determined either.
  const auto undetermined = [&](int index) { return result.data_share[index] < kDeterminedShare; };
  for (int i = 0; i < 3; ++i) {
    if (undetermined(1 + i)) result.centre_of_mass_std_errors[i] = kNaN;
  }
  for (int i = 0; i < 6; ++i) {
    if (undetermined(4 + i) || undetermined(1) || undetermined(2) || undetermined(3)) {
      result.inertia_std_errors[static_cast<std::size_t>(i)] = kNaN;
    }
  }
  return finish();
}

PayloadValidation validate_payload(const Model& model, const ArmParameters& arm, const PayloadResult& payload,
                                   const std::vector<Trajectory>& measured, const PayloadOptions& options) {
  if (measured.empty()) throw InputError("validation", "no run to validate the payload on");
  std::vector<std::optional<Trajectory>> storage;
  std::vector<std::string> warnings;
  const PreparedRuns runs = prepare_runs(measured, options.preparation, storage, warnings);
  const Eigen::VectorXd loaded = with_payload(model, arm, payload.estimate);
  std::vector<TorquePrediction> without, with;
  for (const Trajectory& run : runs) {
    without.push_back(predict_torque(model, arm.layout, arm.pi, run, options.judge, payload.torque_joints));
    with.push_back(predict_torque(model, arm.layout, loaded, run, options.judge, payload.torque_joints));
  }
  return {combine(without), combine(with)};
}

}  // namespace manipid::robot

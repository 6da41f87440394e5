// excitation_internal.h — internal: what the excitation's files share (the Fourier basis on a grid, the
// limit grid and the scaling into the limits, the criterion's workspace), for robot/excitation.h.
//
// The files, by topic:
//   excitation_fourier.cpp    the series: FourierTrajectory, the basis tables, sampling;
//   excitation_limits.cpp     the limits: resolving them (and the options), the grid bound, the largest
//                             scale within them, the torque guard, the checks of a sampled or designed
//                             trajectory;
//   excitation_criterion.cpp  the criterion: the stacked base regressor, its condition number and log det;
//   excitation_design.cpp     the design: the search space, random starts and the local runs (through
//                             estimation/optimizer.h, core's one NLopt adapter), the summary;
//   excitation_ramp.cpp       the start pose: the ramp to the series and back, the design sampled with it.
#pragma once

#include "manipid/core/robot/base_parameters.h"
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/excitation.h"

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

namespace manipid::robot::detail {

inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

inline constexpr int kMinHarmonics = 2;   // the two rest conditions take one coefficient each of a and b
inline constexpr int kMaxHarmonics = 20;  // beyond any published excitation; the optimiser's dimension is n (2L − 1)
inline constexpr int kConstraintPointsPerHarmonic = 64;  // grid points per period of the highest harmonic
inline constexpr int kMaxSamples = 100000;               // the criterion's instants per period
inline constexpr long kMaxSampledInstants = 10'000'000;  // the most samples a sampled excitation has

/// `value` with six significant digits: a figure in a message.
inline std::string format_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

// ---- The series (excitation_fourier.cpp) -------------------------------------------------------

/// Where in each of the N steps of a period the instants fall.
enum class Instants {
  starts,     ///< t_j = T j / N: the sampled trajectory, t = 0 included
  midpoints,  ///< t_j = T (j + ½) / N: the criterion's (see CriterionWorkspace)
};

/// The Fourier basis at N evenly spaced instants of one period, as 2L × N matrices, so that for K = [a b]
/// (n × 2L): p = K·position (q − q0), q̇ = K·velocity, q̈ = K·acceleration, jerk = K·jerk (n × N each).
/// Phases are reduced exactly in integers: ω l t_j = 2π ((l m_j) mod 2N) / 2N with m_j = 2j (starts) or
/// 2j + 1 (midpoints).
struct HarmonicTable {
  Eigen::MatrixXd position, velocity, acceleration, jerk;

  HarmonicTable(double period, int harmonics, int instants, Instants where);
};

/// K = [a b], n × 2L.
Eigen::MatrixXd stacked_coefficients(const FourierTrajectory& trajectory);

// ---- The limits (excitation_limits.cpp) --------------------------------------------------------

/// Peaks of one joint's motion over a period, from a grid plus the bound on what lies between its points
/// (excitation_limits.cpp): an outer bound of the continuous trajectory's extremes.
struct Peaks {
  double highest = 0.0;  ///< max p (p = q − q0)
  double lowest = 0.0;   ///< min p
  double velocity = 0.0;
  double acceleration = 0.0;
  double jerk = 0.0;
};

/// The grid on which the limits are checked, with the inter-sample bounds.
class LimitGrid {
 public:
  LimitGrid(double period, int harmonics);

  /// Outer bounds of each joint's extremes for coefficients K (n × 2L); `work` is scratch (n × grid).
  void peaks(const Eigen::MatrixXd& K, Eigen::MatrixXd& work, std::vector<Peaks>& out) const;

  int points() const { return static_cast<int>(table_.position.cols()); }

 private:
  int harmonics_;
  double omega_;
  double spacing_;
  HarmonicTable table_;
};

/// The largest s ≥ 0 with q0 + s·p inside every kinematic limit of joint k, p's extremes bounded by `peaks`.
double largest_scale(const Peaks& peaks, double q0, const ExcitationLimits& limits, Eigen::Index k);

/// The torque limits on a design: the largest common factor γ ∈ [0, 1] of every joint's motion about q0
/// (q = q0 + γ p) whose torque stays within kTorqueShare of each limit at N instants of a period. One per
/// design; nothing is allocated per call.
class TorqueGuard {
 public:
  TorqueGuard(const Model& model, const ExcitationLimits& limits, double period, int harmonics, int instants);

  /// γ for q0 (n) and K (n × 2L): 1 when the motion as given keeps the limits, else the largest factor
  /// found (within 0.5 %) that does; negative when even the arm at rest at q0 exceeds a limit.
  double largest_factor(const Eigen::VectorXd& q0, const Eigen::MatrixXd& K);

 private:
  /// max over joints and instants of |τ| / (kTorqueShare · limit), for q0 + γ p.
  double ratio(double gamma);

  const Model& model_;
  const ExcitationLimits& limits_;
  HarmonicTable table_;
  Data data_;
  Eigen::MatrixXd p_, v_, a_;
  Eigen::VectorXd q0_, q_, qd_, qdd_, tau_;
};

/// How much of each limit `trajectory` uses (n × 6, LimitKind's order; NaN where there is no limit; see
/// ExcitationSummary::usage), and in `peaks` what it reaches (min q, max q, max |q̇|, |q̈|, |jerk|, |τ|):
/// measured on a grid 4× finer than the limit grid, the torque by inverse dynamics with the limits' model.
Eigen::MatrixXd measured_usage(const Model& model, const FourierTrajectory& trajectory, const ExcitationLimits& limits,
                               Eigen::MatrixXd& peaks);

// ---- The criterion (excitation_criterion.cpp) --------------------------------------------------

/// Multiply-adds between two checkpoints of a long criterion step (about 0.05 s).
inline constexpr double kCheckpointWork = 1e8;

/// N: options.samples, or its documented default for options.harmonics.
inline int resolved_samples(const ExcitationOptions& options) {
  return options.samples > 0 ? options.samples : std::max(200, 40 * options.harmonics);
}

/// The columns the criterion judges: Y_b = Y(:, selected) · transform (transform empty: the selected columns
/// as they are). The arm's: its base parameters' independent columns; a payload's: the last body's ten times
/// payload_to_last_body().
struct CriterionColumns {
  std::vector<int> selected;
  Eigen::MatrixXd transform;  ///< selected.size() × b, or empty
  int size() const { return transform.size() ? static_cast<int>(transform.cols()) : static_cast<int>(selected.size()); }
};
/// The columns options.target asks for on `model` (the base parameters computed with options.cancel). Throws
/// InputError("model") when the arm's torques determine no parameter.
CriterionColumns criterion_columns(const Model& model, const ExcitationOptions& options);

/// The base regressor stacked over N instants of one period, and the criteria from it. One per design
/// (or per quality evaluation): the Data and every matrix are sized once, nothing is allocated per call.
///
/// The instants are the midpoints t_j = T (j + ½) / N — as good a quadrature of a periodic integrand as
/// the starts T j / N, and they avoid t = 0, where the design makes q̇ = 0 exactly: there the Coulomb
/// column sign(q̇) would be sign(±1e-17), decided by rounding (measured: cond moved by 2.5 % between a
/// trajectory and the same one with its rest conditions re-imposed to the last bit).
///
/// Large problems (50 joints, 20 harmonics: Y_b is 40,000 × 446; one Gram product 1 s, one SVD 8 s) are
/// done in row blocks of about kCheckpointWork multiply-adds with a checkpoint of `cancel` between them, so
/// a cancel, a shutdown or a time limit stops them within a fraction of a second (Interrupted); smaller ones
/// run whole, as before.
class CriterionWorkspace {
 public:
  CriterionWorkspace(const Model& model, const ParameterLayout& layout, const CriterionColumns& columns, double period,
                     int harmonics, int samples, const std::atomic<bool>* cancel = nullptr);

  int samples() const { return samples_; }

  /// Fills Y_b for q0 (n) and K = [a b] (n × 2L).
  void stack(const Eigen::VectorXd& q0, const Eigen::MatrixXd& K);

  /// From the stacked Y_b, through the Gram matrix (fast; what the optimiser sees): log cond(Y_b S) and
  /// log det(Y_bᵀ Y_b / N). Squaring loses nothing that matters here: condition numbers up to ~1e7 come
  /// out to several digits, beyond that the trajectory is bad whatever the digits. Capped, never NaN.
  void fast_criteria(double& log_condition, double& log_det);

  /// By SVD of the column-scaled Y_b: the reported figures.
  ExcitationQuality exact_quality() const;

 private:
  /// Rows of Y_b per block of a step whose work is rows × columns²: all of them when that is small.
  Eigen::Index rows_between_checkpoints(Eigen::Index columns) const;

  const Model& model_;
  const ParameterLayout& layout_;
  const CriterionColumns& columns_;
  int n_;
  int samples_;
  HarmonicTable table_;
  Data data_;
  Eigen::MatrixXd q_, qd_, qdd_;
  Eigen::MatrixXd Y_, selected_, Yb_;
  Eigen::MatrixXd gram_, scaled_gram_;
  Eigen::VectorXd norms_;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen_;
  const std::atomic<bool>* cancel_;
};

}  // namespace manipid::robot::detail

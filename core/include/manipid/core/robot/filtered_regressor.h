// filtered_regressor.h — the paper's input-error rows for a rigid-body robot, filtered consistently.
//
// Two filters, each with its own job:
//  - the differentiation filter D (the paper's differential filter, signal/filters.h: M, Ωg) gives q^f,
//    q̇^f, q̈^f, and the regressor is formed from them, Y(q^f, q̇^f, q̈^f). Its band lies far above every
//    comparison band: the windowed differentiators are exact only near DC (the second derivative's gain is
//    off by ~1e-3 across most of its passband, by 1.4e-5 at 2 % of Ωg), and a biased q̈ biases every
//    inertial parameter;
//  - the comparison filter L — a zero-phase Butterworth low-pass at a cut-off f_c (signal/butterworth.h),
//    the judge's family (signal/judge.h) — is applied to τ and to every column of Y alike ("parallel
//    filtering"):
//
//        L τ = L (Y(q, q̇, q̈) π) = (L Y) π   and   L Y(q, q̇, q̈) ≈ L Y(q^f, q̇^f, q̈^f),
//
//    exact for any linear L; the only approximation is Y(q^f, ..) ≈ Y(q, ..), which D's wide band makes
//    good. L decides which frequencies the fit weighs: low, it keeps the torque the motion makes and drops
//    the noise and the vibrations no rigid-body model explains. Without parallel filtering, Y keeps the
//    sharp sign(q̇) edges of Coulomb friction while τ^f has them smoothed, and least squares moves Coulomb
//    friction into viscous (measured: fv +40 %). Unlike a finite window, L costs no samples at the ends, and
//    its start-up transients are the same on both sides (it is linear); the rows still leave out
//    `trim_seconds` at each end (the judge's 0.3 s), where real logs start and stop. Held-out figures of the
//    real arms (bench/real_arms/compare.py, friction v,c,o) with rows trimmed 0 / 0.1 / 0.3 / 0.5 s: Panda
//    1.09 / 1.08 / 1.07 / 1.06 %, KUKA 2.39 / 2.35 / 2.33 / 2.35 %, Kinova 9.03 / 7.25 / 6.27 / 7.49 %,
//    Kinova on two runs 7.36 / 7.53 / 7.14 / 8.72 %.
//
// The working grid: D's output holds nothing above Ωg, so the regressor is formed only at every k-th
// sample, k = max(1, ⌊1 / (4 f_g Δ)⌋) with f_g = Ωg / (2πΔ): four samples per period of D's band edge, so
// that what the regressor's products of two states hold (up to 2 f_g) stays below the working Nyquist
// frequency, and what three make (3 f_g) folds back above 2 f_g ≥ 6 f_c, where L removes it; τ goes through
// an anti-aliasing low-pass at a quarter of the working rate before it is sampled there (its gain differs
// from 1 by < 2e-4 below f_c, as f_g ≥ 3 f_c).
// After L every r-th working sample is a row block, r = max(1, ⌊1 / (5 f_c Δ_w)⌋): above 2.5 f_c the
// filtered signals hold less than 1e-3 of their power, so no information is lost.
#pragma once

#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/signal/filters.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <atomic>
#include <vector>

namespace manipid::robot {

/// The two filters and the grids they work on.
struct FilterPair {
  FilterSettings differentiation;    ///< D: half-length M, band Ωg (rad/sample), Δ the data's period
  double comparison_cutoff_hz = 0.0; ///< L's cut-off f_c, Hz
  int working_step = 1;              ///< k: the regressor is formed at every k-th sample of D's output
  double trim_seconds = 0.3;         ///< L's start-up trimmed at each end of D's output, s
  double working_dt() const { return differentiation.dt * working_step; }
  /// The shortest data (samples) the pair can filter: D's 2M + 1 taps and two trims with rows between.
  int shortest_data() const;
};

/// The rule for D given the highest comparison cut-off it must serve: f_g = 3 · highest (at most Ωg = π/2),
/// M = ⌈6.4π/Ωg⌉ (the paper's M = 100, Ωg = 0.2 proportion), and the working step of the file comment.
FilterPair differentiation_for(double highest_cutoff_hz, double dt, double trim_seconds);
/// The working step k of the file comment for a differentiation filter D.
int working_step(const FilterSettings& differentiation);

/// The comparison cut-offs a held-out choice tries, as multiples of the judge's cut-off (5 Hz: 1.5 .. 10 Hz).
inline constexpr double kCutoffFactors[] = {0.3, 0.4, 0.6, 0.8, 1.0, 1.4, 2.0};
/// The candidates: `given_hz` alone when it is > 0, else kCutoffFactors × the judge's cut-off below a fifth
/// of the Nyquist frequency (at least one: the judge's, or that fifth).
std::vector<double> candidate_cutoffs(double given_hz, double judge_cutoff_hz, double dt);
/// The held-out choice's folds and the time bins each is made of (estimation/cross_validation.h).
inline constexpr int kHeldOutFolds = 5;
inline constexpr int kHeldOutBinsPerFold = 4;
/// The time a fold's training rows keep from its tested segment, s: half a period of each low-pass (the
/// candidate's and the judge's) and D's half-length — what a row shares with its neighbours.
double held_out_guard(double cutoff_hz, double judge_cutoff_hz, const FilterPair& filters);

/// One run on the working grid, before L: the regressor's non-zero columns and the torque.
struct RegressorSignals {
  double dt = 0.0;                          ///< the working period Δ_w, s
  Eigen::VectorXd t;                        ///< the working samples' times, s
  std::vector<std::vector<int>> columns;    ///< per joint k: the standard indices of row k's non-zero columns
  std::vector<Eigen::MatrixXd> Y;           ///< per joint k: samples × columns[k]
  Eigen::MatrixXd tau;                      ///< samples × n, anti-aliased (empty when the data has no torque)
};

/// D over `data` (uniform samples: prepare_data first), the working grid, Y there. Throws InputError when
/// the data is shorter than filters.shortest_data(), the joint counts differ, or the settings are invalid.
/// Returns with empty `t` when `cancel` is set part way.
RegressorSignals regressor_signals(const Model& model, const ParameterLayout& layout, const Trajectory& data,
                                   const FilterPair& filters, const std::atomic<bool>* cancel = nullptr);

/// The rows least squares compares: (L Y) π against L τ for the joints given, joint-major within each kept
/// instant.
struct FilteredRows {
  Eigen::VectorXd t;        ///< R: each row block's time, s
  std::vector<int> joints;  ///< the joints (0-based) whose rows are kept, in order
  Eigen::MatrixXd W;        ///< (R · joints) × the columns asked for (filtered_rows(); all: dim π)
  Eigen::VectorXd tau;      ///< R · joints: L τ at the same rows
  int row_step = 1;         ///< r: every r-th working sample is a row block
  /// Σ h² of L's (zero-phase) impulse response on the working grid: white noise through L keeps this share.
  double lowpass_energy = 1.0;
};

/// L at `cutoff_hz` over `signals` (Y's columns and τ), `trim_seconds` dropped at each end, every
/// r-th instant (the file comment), the rows of `joints`; W's columns are the standard parameters `columns`
/// in that order (empty: all of π, `parameter_count` of them) — a regressor column costs one low-pass over
/// the whole run, so only those asked for are filtered. Throws InputError ("comparison_cutoff") for a cut-off
/// at or above the working grid's Nyquist frequency, InputError ("samples") when nothing is left after the
/// trims.
FilteredRows filtered_rows(const RegressorSignals& signals, int parameter_count, double cutoff_hz, double trim_seconds,
                           const std::vector<int>& joints, const std::vector<int>& columns = {});

}  // namespace manipid::robot

// filtered_regressor.h — the paper's input-error filtering for a rigid-body robot, filtered consistently.
//
// The measured angles go through the differential filters (filters.h): q^f, q̇^f, q̈^f. The regressor is
// formed from them, Y(q^f, q̇^f, q̈^f). Then — the step that makes the comparison consistent — the same
// low-pass L that gives τ^f = L τ is applied to every column of Y ("parallel filtering"):
//
//     L τ = L (Y(q, q̇, q̈) π) = (L Y) π   and   L Y(q, q̇, q̈) ≈ L Y(q^f, q̇^f, q̈^f)
//
// as long as the band passes the motion (q^f ≈ q). Without it, Y keeps the sharp sign(q̇) edges of Coulomb
// friction and the products of the nonlinear terms while τ^f has them smoothed, and least squares moves
// Coulomb friction into viscous (measured: fv +40 %). Filtered twice, the regressor's valid samples start
// 2M after the data's; τ^f is taken at the same instants.
//
// The doubly filtered signals hold nothing above the band Ωg, so keeping every D-th row with
// D = max(1, ⌊π / (2 Ωg)⌋) (twice the Nyquist rate of the band) loses no information while cutting the
// least-squares work by D. The rows are accumulated sample by sample (each Y(q^f_s) added to the ≈ (2M+1)/D
// outputs whose window covers s), so memory stays O(rows × dim π) whatever the number of samples.
#pragma once

#include "manipid/core/filters.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/trajectory.h"

#include <Eigen/Core>

#include <atomic>

namespace manipid::robot {

/// The rows least squares compares: (L Y) π against L τ, joint-major within each kept instant.
struct FilteredRegressor {
  FilterSettings filter;
  int decimation = 1;        ///< D: every D-th doubly filtered instant is a row block
  int instants = 0;          ///< R: row blocks; rows = R · n
  Eigen::VectorXd t;         ///< R: the time of each row block, s
  Eigen::MatrixXd W;         ///< (R · n) × dim π: row r·n + k−1 is joint k at instant r
  Eigen::VectorXd tau;       ///< R · n: L τ at the same rows (empty when the data has no torque)
  /// Σ c² of the low-pass taps: white noise through L keeps this share of its variance.
  double lowpass_energy = 1.0;
};

/// Builds the rows for `data` (uniform samples: prepare_data first). Throws InputError when the data is
/// too short for two passes of the filter (4M + 2 samples), the joint counts differ, or the settings are
/// invalid. Returns with `instants` = 0 when `cancel` is set part way.
FilteredRegressor filtered_regressor(const Model& model, const ParameterLayout& layout, const Trajectory& data,
                                     const FilterSettings& filter, const std::atomic<bool>* cancel = nullptr);

/// What a parameter vector predicts against the measured torque, both through the same filters.
struct TorquePrediction {
  Eigen::VectorXd t;         ///< times of the compared instants, s
  Eigen::MatrixXd measured;  ///< L τ, instants × n
  Eigen::MatrixXd model;     ///< L Y(q^f, q̇^f, q̈^f) π, instants × n
  Eigen::VectorXd rms_error;       ///< per joint, N·m (N)
  Eigen::VectorXd relative_error;  ///< per joint ‖τ̂ − τ^f‖ / ‖τ^f‖
  double overall_relative_error = 0.0;  ///< ‖τ̂ − τ^f‖_F / ‖τ^f‖_F over every joint
};

/// The torque `pi` predicts on `data` (uniform samples with torque), filtered as identification filters
/// (every doubly filtered instant, no decimation), beside the measured torque and the error figures.
TorquePrediction predict_torque(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi,
                                const Trajectory& data, const FilterSettings& filter);

}  // namespace manipid::robot

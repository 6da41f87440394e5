// input_error.h — the paper's input-error cost (its eq. 5, discrete), in Gram form.
//
// With filtered signals q^f, q̇^f, q̈^f, τ^f (N' samples) and the regressor Y_t (regressor.h),
//     J(θ) = Σ_j w_j · (1/N') Σ_t (Y_t β(θ) − τ^f_t)_j²  =  |R β(θ) − z|² + J⊥,
// where QR = (1/√N') [√W Y_t]_t is a QR factorisation of the stacked weighted regressor,
// z = Qᵀ(1/√N')[√W τ^f_t]_t, and J⊥ the part of the torque no β can reach. R (dim β square),
// z and J⊥ are computed once, so an evaluation (and its gradient 2 Gᵀ Rᵀ (R β − z),
// G = ∂β/∂θ) costs O(dim β²) whatever the number of samples. This is the Gram form
// βᵀAβ − 2bᵀβ + c with A = RᵀR, kept factored: forming A squares its condition number, and
// the paper's model makes A ill-conditioned enough to lose five digits of the cost that way.
#pragma once

#include "manipid/core/signal/filters.h"
#include "manipid/core/paper/model.h"
#include "manipid/core/paper/regressor.h"
#include "manipid/core/paper/simulation.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <optional>

namespace manipid {

/// Filtered signals for input-error identification; matrices are samples × joints.
struct FilteredData {
  FilterSettings filter;
  Eigen::MatrixXd q, qd, qdd, tau;
  int samples() const { return static_cast<int>(q.rows()); }
};

/// Filters q (orders 0, 1, 2) and forms τ^f: the low-passed measured torque, or — the paper's
/// way — τ^f = Kp (r^f − q^f) − Kd q̇^f from the reference when `controller` is given and
/// `use_reference` is set. Throws InputError when data or gains do not fit.
FilteredData filter_for_input_error(const Trajectory& data, const FilterSettings& filter, bool use_reference,
                                    const std::optional<PdController>& controller);

/// What the input-error cost compares, sample by sample, at one parameter value: the filtered
/// measured torque τ^f and the model torque τ̂(q^f, q̇^f, q̈^f, θ), samples × joints, with the
/// time of each filtered sample (output j of the filter belongs to input sample M + j).
struct TorqueFit {
  Eigen::VectorXd t;
  Eigen::MatrixXd measured, model;
  Eigen::MatrixXd residual() const { return model - measured; }
};

/// τ^f beside τ̂ at `parameters`; `filtered` comes from filter_for_input_error(data, ...).
TorqueFit torque_fit(const RobotModel& model, const Parameters& parameters, const Trajectory& data,
                     const FilteredData& filtered);

class InputErrorCost {
 public:
  /// `joint_weights` has one entry per joint (w_j ≥ 0); empty means all 1. Keeps `data` (moved
  /// in when the caller has no more use for it).
  InputErrorCost(const RobotModel& model, FilteredData data, Eigen::VectorXd joint_weights = {});

  /// J(θ) in Gram form; with `gradient`, also ∂J/∂θ (2n entries, θ order).
  double evaluate(const Parameters& parameters, Eigen::VectorXd* gradient = nullptr) const;
  /// The same cost as a sum of squares, J(θ) = |r|² + J⊥ with r = R β(θ) − z (dim β entries); with
  /// `jacobian`, also ∂r/∂θ = R G (dim β × 2n): what Levenberg–Marquardt works on.
  Eigen::VectorXd residual(const Parameters& parameters, Eigen::MatrixXd* jacobian = nullptr) const;
  /// J⊥: the part of the torque no β reaches, the constant beside |r|².
  double orthogonal() const { return orthogonal_; }
  /// J(θ) sample by sample with inverse_dynamics: the reference the Gram form is tested against.
  double evaluate_direct(const Parameters& parameters) const;

  /// Gauss–Newton Hessian of the sum of squares, J_rᵀ J_r = N' Gᵀ A G (2n × 2n).
  Eigen::MatrixXd gauss_newton_matrix(const Parameters& parameters) const;
  /// Residual count N'·n.
  long residual_count() const { return static_cast<long>(data_.samples()) * model_.joint_count(); }
  /// The smallest cost any β reaches (J*): what no parameter value can explain.
  double floor() const { return floor_; }

  const ParameterProducts& products() const { return products_; }
  const FilteredData& data() const { return data_; }
  const RobotModel& model() const { return model_; }

 private:
  RobotModel model_;
  FilteredData data_;
  Eigen::VectorXd weights_;
  ParameterProducts products_;
  Eigen::MatrixXd triangle_;   // R
  Eigen::VectorXd rotated_;    // z
  double orthogonal_ = 0.0;    // J⊥
  double floor_ = 0.0;         // J* = J⊥ + min_β |R β − z|²
};

}  // namespace manipid

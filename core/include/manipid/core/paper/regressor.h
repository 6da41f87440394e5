// regressor.h — the torque as a linear function of parameter products.
//
// With point masses at the frame origins and J_k = c m_k l_k², every torque is linear in
// products of parameters β(θ) = (m_k, m_k·l_a, m_k·l_a·l_b):
//
//     τ(q, q̇, q̈, θ) = Y(q, q̇, q̈) β(θ).
//
// Y depends only on the measured motion, so identification can accumulate YᵀY once over
// the data and then evaluate its cost in O(dim β²), independent of the number of samples.
// The products that can occur follow from the model's structure (which links move which
// masses, which offsets are fixed); a column that the structure admits but this model
// never excites (gravity parallel to an axis, say) may be identically zero.
#pragma once

#include "manipid/core/paper/dynamics.h"
#include "manipid/core/paper/model.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace manipid {

/// The constant map θ → β(θ) for one model.
struct ParameterProducts {
  /// One column of Y: β_i = m_mass · l_first · l_second, where a length index of -1 means
  /// the factor 1 (m_k alone, or m_k·l_a).
  struct Term {
    int mass = 0;     ///< 0-based joint index of the mass
    int first = -1;   ///< 0-based length index, or -1
    int second = -1;  ///< 0-based length index (≥ first when both are set), or -1
  };
  std::vector<Term> terms;
  int joint_count = 0;
  /// (mass, first + 1, second + 1) → column, or -1; filled by parameter_products().
  std::vector<int> lookup;
  /// The model's link vectors (link, length index or -1 for fixed offsets) that regressor()
  /// expands the kinematics into; filled by parameter_products().
  struct LinkSymbol {
    int link = 0;
    int length = -1;
  };
  std::vector<LinkSymbol> symbols;
  /// For link vectors s and r (r = −1: none, as gravity's terms m_k·λ_s), the columns of
  /// m_k·λ_s·λ_r for every mass k both move (k from the later link on), ascending in k:
  /// pair_columns[pair_offsets[p] … pair_offsets[p + 1]), p = s·(symbols + 1) + r + 1. Filled by
  /// parameter_products(); what regressor() adds each product's value to.
  std::vector<int> pair_columns, pair_offsets;

  int size() const { return static_cast<int>(terms.size()); }
  /// "m2*l2*l3", "m4*l3", "m1*l1^2", ... (1-based names, as users see them).
  std::string name(int column) const;
  /// Column of a term, or -1 if the model has no such product.
  int column(int mass, int first, int second) const;

  /// β(θ).
  Eigen::VectorXd evaluate(const Parameters& parameters) const;
  /// ∂β/∂θ: dim β × 2n, θ ordered as Parameters::vector().
  Eigen::MatrixXd jacobian(const Parameters& parameters) const;
};

/// The products that the model's torque can depend on.
ParameterProducts parameter_products(const RobotModel& model);

/// Y(q, q̇, q̈): n × dim β, such that inverse_dynamics = Y · products.evaluate(θ).
/// Y depends on the link lengths only through fixed DH offsets, never through θ.
void regressor(const RobotModel& model, const ParameterProducts& products,
               DynamicsWorkspace& workspace, const Eigen::Ref<const Eigen::VectorXd>& q,
               const Eigen::Ref<const Eigen::VectorXd>& qd,
               const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y);
Eigen::MatrixXd regressor(const RobotModel& model, const ParameterProducts& products,
                          const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                          const Eigen::VectorXd& qdd);

/// Y at many samples: sample t's state is row t of q, qd and qdd (samples × n), its n rows of
/// Y are rows t·n … t·n + n − 1 of `Y` ((samples·n) × dim β). The numbers regressor() gives at
/// each sample (but for the sign of a zero), computed four samples at a time: ~1.7× faster a sample.
void regressor_rows(const RobotModel& model, const ParameterProducts& products, DynamicsWorkspace& workspace,
                    const Eigen::Ref<const Eigen::MatrixXd>& q, const Eigen::Ref<const Eigen::MatrixXd>& qd,
                    const Eigen::Ref<const Eigen::MatrixXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y);

}  // namespace manipid

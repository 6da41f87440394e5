// regressor.cpp — Y(q, q̇, q̈) with τ = Y π, for one sample and stacked over many (robot/regressor.h).
#include "manipid/core/robot/regressor.h"

#include "robot/forward_pass.h"
#include "manipid/core/robot/rnea.h"
#include "robot/skew.h"

namespace manipid::robot {
namespace {

using BodyMatrix = Eigen::Matrix<double, 6, kInertialParametersPerBody>;  // (force; moment) per parameter

/// L(w) with I w = L(w) (Ixx, Ixy, Ixz, Iyy, Iyz, Izz)ᵀ.
inline Eigen::Matrix<double, 3, 6> inertia_operator(const Eigen::Vector3d& w) {
  Eigen::Matrix<double, 3, 6> L;
  L << w.x(), w.y(), w.z(), 0.0, 0.0, 0.0,  //
      0.0, w.x(), 0.0, w.y(), w.z(), 0.0,    //
      0.0, 0.0, w.x(), 0.0, w.y(), w.z();
  return L;
}

/// Body k's Newton–Euler wrench about its origin, in its frame, as a linear map of its 10 parameters:
///   f = a m + ([ω̇]× + [ω]×²) h,   n = −[a]× h + (L(ω̇) + [ω]× L(ω)) I.
inline BodyMatrix body_matrix(const Eigen::Vector3d& w, const Eigen::Vector3d& dw, const Eigen::Vector3d& a) {
  BodyMatrix A = BodyMatrix::Zero();
  const Eigen::Matrix3d W = skew(w);
  A.block<3, 1>(0, 0) = a;
  A.block<3, 3>(0, 1) = skew(dw) + W * W;
  A.block<3, 3>(3, 1) = -skew(a);
  A.block<3, 6>(3, 4) = inertia_operator(dw) + W * inertia_operator(w);
  return A;
}

/// Fills Y (n × layout.size(n)) after the sizes have been checked.
void fill_regressor(const Model& model, Data& data, const ParameterLayout& layout,
                    const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
                    const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y) {
  const int n = model.joint_count();
  detail::forward_pass(model, data, q, qd, qdd);
  Y.setZero();
  // Body k's wrench per parameter, carried inward joint by joint: at each joint j ≤ k, its projection on
  // the axis (moment for revolute, force for prismatic) is row j of block k; then the wrench moves to
  // body j−1's frame: f' = R f, n' = R n + p × f'.
  for (int k = n - 1; k >= 0; --k) {
    BodyMatrix W = body_matrix(data.angular_velocity[k], data.angular_acceleration[k], data.proper_acceleration[k]);
    const int column = kInertialParametersPerBody * k;
    for (int j = k;; --j) {
      const Joint& joint = model.joints[j];
      Y.block<1, kInertialParametersPerBody>(j, column).noalias() =
          joint.axis.transpose() * (joint.is_prismatic() ? W.topRows<3>() : W.bottomRows<3>());
      if (j == 0) break;
      const Eigen::Matrix3d& R = data.rotation[j];
      Eigen::Matrix<double, 3, kInertialParametersPerBody> force;
      force.noalias() = R * W.topRows<3>();
      W.bottomRows<3>() = R * W.bottomRows<3>() + skew(data.translation[j]) * force;
      W.topRows<3>() = force;
    }
  }
  for (int k = 0; k < n; ++k) {
    if (layout.viscous) Y(k, layout.viscous_begin(n) + k) = qd[k];
    if (layout.coulomb) Y(k, layout.coulomb_begin(n) + k) = friction_sign(qd[k]);
    if (layout.offset) Y(k, layout.offset_begin(n) + k) = 1.0;
    if (layout.armature) Y(k, layout.armature_begin(n) + k) = qdd[k];
  }
}

void check_matrix(const char* field, const Eigen::Ref<const Eigen::MatrixXd>& m, Eigen::Index rows, Eigen::Index cols) {
  if (m.rows() != rows || m.cols() != cols) {
    throw InputError(field, std::string(field) + " is " + std::to_string(m.rows()) + " × " + std::to_string(m.cols()) +
                                ", expected " + std::to_string(rows) + " × " + std::to_string(cols));
  }
}

}  // namespace

void regressor(const Model& model, Data& data, const ParameterLayout& layout,
               const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
               const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y) {
  const int n = model.joint_count();
  detail::check_data(model, data);
  detail::check_size("q", q.size(), n);
  detail::check_size("qd", qd.size(), n);
  detail::check_size("qdd", qdd.size(), n);
  check_matrix("Y", Y, n, layout.size(n));
  fill_regressor(model, data, layout, q, qd, qdd, Y);
}

Eigen::MatrixXd regressor(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& q,
                          const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  Data data(model);
  Eigen::MatrixXd Y(model.joint_count(), layout.size(model.joint_count()));
  regressor(model, data, layout, q, qd, qdd, Y);
  return Y;
}

void stacked_regressor(const Model& model, Data& data, const ParameterLayout& layout,
                       const Eigen::Ref<const Eigen::MatrixXd>& q, const Eigen::Ref<const Eigen::MatrixXd>& qd,
                       const Eigen::Ref<const Eigen::MatrixXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y) {
  const int n = model.joint_count();
  const Eigen::Index samples = q.cols();
  detail::check_data(model, data);
  check_matrix("q", q, n, samples);
  check_matrix("qd", qd, n, samples);
  check_matrix("qdd", qdd, n, samples);
  check_matrix("Y", Y, samples * n, layout.size(n));
  for (Eigen::Index s = 0; s < samples; ++s) {
    fill_regressor(model, data, layout, q.col(s), qd.col(s), qdd.col(s), Y.middleRows(s * n, n));
  }
}

Eigen::MatrixXd stacked_regressor(const Model& model, const ParameterLayout& layout, const Eigen::MatrixXd& q,
                                  const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qdd) {
  Data data(model);
  Eigen::MatrixXd Y(q.cols() * model.joint_count(), layout.size(model.joint_count()));
  stacked_regressor(model, data, layout, q, qd, qdd, Y);
  return Y;
}

}  // namespace manipid::robot

// rnea.cpp — recursive Newton–Euler inverse dynamics in the standard parameters (robot/rnea.h).
#include "manipid/core/robot/rnea.h"

#include "robot/forward_pass.h"

namespace manipid::robot {
namespace {

/// I w for the inertia tensor whose entries (Ixx, Ixy, Ixz, Iyy, Iyz, Izz) start at I.
inline Eigen::Vector3d inertia_times(const double* I, const Eigen::Vector3d& w) {
  return {I[0] * w.x() + I[1] * w.y() + I[2] * w.z(),  //
          I[1] * w.x() + I[3] * w.y() + I[4] * w.z(),  //
          I[2] * w.x() + I[4] * w.y() + I[5] * w.z()};
}

}  // namespace

void inverse_dynamics(const Model& model, Data& data, const ParameterLayout& layout,
                      const Eigen::Ref<const Eigen::VectorXd>& pi, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& qdd,
                      Eigen::Ref<Eigen::VectorXd> tau) {
  const int n = model.joint_count();
  detail::check_data(model, data);
  detail::check_size("pi", pi.size(), layout.size(n));
  detail::check_size("q", q.size(), n);
  detail::check_size("qd", qd.size(), n);
  detail::check_size("qdd", qdd.size(), n);
  detail::check_size("tau", tau.size(), n);

  detail::forward_pass(model, data, q, qd, qdd);

  // Inward sweep: Newton–Euler about each body's origin, in its frame, plus what its child carries.
  //   f_k = m a_k + ω̇_k × h + ω_k × (ω_k × h) + R_{k,k+1} f_{k+1}
  //   n_k = I ω̇_k + ω_k × (I ω_k) + h × a_k + R_{k,k+1} n_{k+1} + p_{k,k+1} × (R_{k,k+1} f_{k+1})
  // with a_k the proper acceleration (gravity included) and (m, h, I) body k's standard parameters.
  Eigen::Vector3d child_force = Eigen::Vector3d::Zero(), child_moment = Eigen::Vector3d::Zero();
  for (int k = n - 1; k >= 0; --k) {
    const double* body = pi.data() + kInertialParametersPerBody * k;
    const double mass = body[0];
    const Eigen::Vector3d h(body[1], body[2], body[3]);
    const Eigen::Vector3d& w = data.angular_velocity[k];
    const Eigen::Vector3d& dw = data.angular_acceleration[k];
    const Eigen::Vector3d& a = data.proper_acceleration[k];
    Eigen::Vector3d f = mass * a + dw.cross(h) + w.cross(w.cross(h));
    Eigen::Vector3d m = inertia_times(body + 4, dw) + w.cross(inertia_times(body + 4, w)) + h.cross(a);
    if (k + 1 < n) {
      const Eigen::Matrix3d& R = data.rotation[k + 1];
      const Eigen::Vector3d carried = R * child_force;
      f += carried;
      m += R * child_moment + data.translation[k + 1].cross(carried);
    }
    data.force[k] = child_force = f;
    data.moment[k] = child_moment = m;
    const Joint& joint = model.joints[k];
    tau[k] = joint.axis.dot(joint.is_prismatic() ? f : m);
  }

  if (layout.viscous) tau += pi.segment(layout.viscous_begin(n), n).cwiseProduct(qd);
  if (layout.coulomb) {
    const double* fc = pi.data() + layout.coulomb_begin(n);
    for (int k = 0; k < n; ++k) tau[k] += fc[k] * friction_sign(qd[k]);
  }
  if (layout.offset) tau += pi.segment(layout.offset_begin(n), n);
  if (layout.armature) tau += pi.segment(layout.armature_begin(n), n).cwiseProduct(qdd);
}

Eigen::VectorXd inverse_dynamics(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi,
                                 const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  Data data(model);
  Eigen::VectorXd tau(model.joint_count());
  inverse_dynamics(model, data, layout, pi, q, qd, qdd, tau);
  return tau;
}

}  // namespace manipid::robot

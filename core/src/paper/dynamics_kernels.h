// dynamics_kernels.h — internal: the complete model's inverse and forward dynamics,
// templated on the joint count (dynamics.cpp dispatches).
//
// Why templates: with the joint count N known at compile time the scratch lives on the
// stack, the mass matrix and its Cholesky factor are fixed-size, and nothing goes through
// Ref<VectorXd> or std::vector inside the recursions. For the paper's robot (callgrind,
// instructions per call) inverse dynamics went from ~1,990 to ~1,550, of which ~460 are the
// four sincos calls, and forward dynamics from ~5,140 to ~2,260. N = Eigen::Dynamic runs the
// same code over DynamicsWorkspace::GeneralSizeScratch, for any joint count; both take their
// scratch through a `Storage` with the members of FixedStorage<N>.
//
// The functions are always inlined, so that dynamics.cpp's AVX2 copy compiles them too.
// Everything is in base coordinates, as in dynamics.cpp: joint k (0-based) turns about the
// axis z_k of frame k and carries mass k at the end of the arm o_{k+1} − o_k.
#pragma once

#include "manipid/core/paper/dynamics.h"

#include <Eigen/Core>

#include <array>
#include <cmath>

namespace manipid::detail {

/// Scratch for N joints, on the stack; DynamicsWorkspace::GeneralSizeScratch has the same
/// members at run-time size.
template <int N>
struct FixedStorage {
  Eigen::Matrix<double, N, 1> joint_sin, joint_cos;  // of q_k
  Eigen::Matrix<double, N, 1> link_a, link_d;        // DH offsets with the lengths substituted
  Eigen::Matrix<double, N, 1> bias;                  // c(q, q̇) + g(q)
  std::array<Eigen::Vector3d, N> joint_axis;         // z_k
  std::array<Eigen::Vector3d, N> link_arm;           // o_{k+1} − o_k
  std::array<Eigen::Vector3d, N> mass_acceleration;  // ö_{k+1} − gravity
  std::array<Eigen::Vector3d, N> mass_jacobian;      // ∂o_{k+1}/∂q_j for one k, all j ≤ k
  Eigen::Matrix<double, N, N> mass_matrix;           // lower triangle
  Eigen::Matrix<double, N, N> cholesky_factor;       // lower triangle
};

template <int N>
inline int joint_count(const RobotModel& model) {
  return N == Eigen::Dynamic ? model.joint_count() : N;
}

/// Sine and cosine of one angle. glibc's sincos shares the argument reduction between the
/// two and returns bit for bit what sin and cos return; the compiler does not fuse separate
/// sin and cos calls by itself (errno semantics).
inline void sine_cosine(double angle, double& sine, double& cosine) {
#ifdef __GLIBC__
  ::sincos(angle, &sine, &cosine);
#else
  sine = std::sin(angle);
  cosine = std::cos(angle);
#endif
}

/// Offsets a_k and d_k of joint k's DH row, with the length parameter substituted.
inline void link_offsets(const RobotModel& model, const Parameters& parameters, int k, double& a, double& d) {
  const JointDescription& joint = model.joints[k];
  a = joint.length_role == LengthRole::a ? parameters.length[k] : joint.a;
  d = joint.length_role == LengthRole::d ? parameters.length[k] : joint.d;
}

inline double joint_inertia(const RobotModel& model, const Parameters& parameters, int k) {
  return model.joint_inertia_factor * parameters.mass[k] * parameters.length[k] * parameters.length[k];
}

// A plain 3-vector for the arithmetic of the kernels. Eigen::Vector3d splits into a SIMD
// pair plus a scalar and spends many instructions on shuffles in the cross products; three
// scalars compile to straight scalar code. Storage stays Eigen::Vector3d.
struct Vec3 {
  double x = 0.0, y = 0.0, z = 0.0;
};
inline Vec3 operator+(const Vec3& a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(double scale, const Vec3& a) { return {scale * a.x, scale * a.y, scale * a.z}; }
inline Vec3& operator+=(Vec3& a, const Vec3& b) { return a = a + b; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 load(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
inline void store(const Vec3& a, Eigen::Vector3d& v) {
  v.x() = a.x;
  v.y() = a.y;
  v.z() = a.z;
}

/// One forward pass: frames (joint_axis, link_arm) and the accelerations of the masses
/// relative to gravity (mass_acceleration). Without `Accelerating`, q̈ = 0 (the bias) and
/// `qdd` is not read.
template <int N, bool Accelerating, class Storage>
[[gnu::always_inline]] inline void forward_pass(const RobotModel& model, const Parameters& parameters, const DynamicsWorkspace& w,
                         const double* q, const double* qd, const double* qdd, Storage& s) {
  const int n = joint_count<N>(model);
  // The library calls and the branches first, so that the arithmetic below runs in registers.
  for (int k = 0; k < n; ++k) {
    sine_cosine(q[k], s.joint_sin[k], s.joint_cos[k]);
    link_offsets(model, parameters, k, s.link_a[k], s.link_d[k]);
  }
  const double* twist_cos = w.twist_cos.data();
  const double* twist_sin = w.twist_sin.data();
  const Vec3 gravity = load(model.gravity);
  // Frame 0 is the base: axes along the base's, at rest.
  Vec3 x{1.0, 0.0, 0.0};
  Vec3 y{0.0, 1.0, 0.0};
  Vec3 z{0.0, 0.0, 1.0};
  Vec3 omega, omega_rate, acceleration;
  for (int k = 0; k < n; ++k) {
    const Vec3 axis = z;
    // Frame k+1 = frame k · Rz(q_k) · Rx(alpha_k); the new x axis is unchanged by the twist.
    const double cosine = s.joint_cos[k];
    const double sine = s.joint_sin[k];
    const Vec3 turned_x = cosine * x + sine * y;
    const Vec3 turned_y = cosine * y - sine * x;
    x = turned_x;
    // Untwisted joints and zero offsets are common (the paper's robot: three of four joints
    // untwisted, no d offsets); skipping them gives the same numbers and saves a third.
    if (twist_sin[k] == 0.0 && twist_cos[k] == 1.0) {
      y = turned_y;
    } else {
      y = twist_cos[k] * turned_y + twist_sin[k] * axis;
      z = twist_cos[k] * axis - twist_sin[k] * turned_y;
    }
    Vec3 arm;
    if (s.link_a[k] != 0.0) arm = s.link_a[k] * x;
    if (s.link_d[k] != 0.0) arm += s.link_d[k] * axis;
    store(axis, s.joint_axis[k]);
    store(arm, s.link_arm[k]);
    // Rates: ω̇ picks up q̈ z and the axis turning with the previous links (ω × q̇ z).
    omega_rate += qd[k] * cross(omega, axis);
    if constexpr (Accelerating) omega_rate += qdd[k] * axis;
    omega += qd[k] * axis;
    acceleration += cross(omega_rate, arm) + cross(omega, cross(omega, arm));
    store(acceleration - gravity, s.mass_acceleration[k]);
  }
}

/// Backward pass: τ_j = z_j · Σ_{k≥j} (o_{k+1} − o_j) × m_k (ö_{k+1} − gravity) + J_j q̈_j,
/// written to tau[0..n); the J_j q̈_j term only when `Accelerating`.
template <int N, bool Accelerating, class Storage, class Output>
[[gnu::always_inline]] inline void backward_pass(const RobotModel& model, const Parameters& parameters, const double* qdd,
                          const Storage& s, Output& tau) {
  const int n = joint_count<N>(model);
  const double* mass = parameters.mass.data();
  const double* length = parameters.length.data();
  Vec3 force;   // Σ_{k≥j} m_k (ö_{k+1} − g)
  Vec3 moment;  // of that force about o_j
  for (int j = n - 1; j >= 0; --j) {
    force += mass[j] * load(s.mass_acceleration[j]);
    moment += cross(load(s.link_arm[j]), force);
    double torque = dot(load(s.joint_axis[j]), moment);
    if constexpr (Accelerating) torque += model.joint_inertia_factor * mass[j] * length[j] * length[j] * qdd[j];
    tau[j] = torque;
  }
}

/// M(q) = Σ_k m_k J_kᵀ J_k + diag(J_j) from the frames of forward_pass, with the position
/// Jacobians J_kj = z_j × (o_{k+1} − o_j). Lower triangle only.
template <int N, class Storage>
[[gnu::always_inline]] inline void lower_mass_matrix(const RobotModel& model, const Parameters& parameters, Storage& s) {
  const int n = joint_count<N>(model);
  s.mass_matrix.setZero();
  for (int k = 0; k < n; ++k) {
    Vec3 reach;  // o_{k+1} − o_j, summed from the mass inwards
    for (int j = k; j >= 0; --j) {
      reach += load(s.link_arm[j]);
      store(cross(load(s.joint_axis[j]), reach), s.mass_jacobian[j]);
    }
    const double m = parameters.mass[k];
    for (int i = 0; i <= k; ++i) {
      const Vec3 momentum = m * load(s.mass_jacobian[i]);
      for (int j = 0; j <= i; ++j) s.mass_matrix(i, j) += dot(momentum, load(s.mass_jacobian[j]));
    }
    s.mass_matrix(k, k) += joint_inertia(model, parameters, k);
  }
}

/// Solves M x = b in place (x holds b on entry) by Cholesky from M's lower triangle, into
/// `factor`. Returns false, leaving x undefined, when M is not positive definite.
template <class Matrix, class Vector>
[[gnu::always_inline]] inline bool cholesky_solve(int n, const Matrix& mass, Matrix& factor, Vector& x) {
  for (int j = 0; j < n; ++j) {
    double diagonal = mass(j, j);
    for (int k = 0; k < j; ++k) diagonal -= factor(j, k) * factor(j, k);
    if (!(diagonal > 0.0)) return false;
    factor(j, j) = std::sqrt(diagonal);
    for (int i = j + 1; i < n; ++i) {
      double entry = mass(i, j);
      for (int k = 0; k < j; ++k) entry -= factor(i, k) * factor(j, k);
      factor(i, j) = entry / factor(j, j);
    }
  }
  for (int i = 0; i < n; ++i) {  // L y = b
    for (int k = 0; k < i; ++k) x[i] -= factor(i, k) * x[k];
    x[i] /= factor(i, i);
  }
  for (int i = n - 1; i >= 0; --i) {  // Lᵀ x = y
    for (int k = i + 1; k < n; ++k) x[i] -= factor(k, i) * x[k];
    x[i] /= factor(i, i);
  }
  return true;
}

template <int N, class Storage, class Output>
[[gnu::always_inline]] inline void complete_inverse_dynamics(const RobotModel& model, const Parameters& parameters,
                                      const DynamicsWorkspace& w, const double* q, const double* qd,
                                      const double* qdd, Storage& s, Output& tau) {
  forward_pass<N, true>(model, parameters, w, q, qd, qdd, s);
  backward_pass<N, true>(model, parameters, qdd, s, tau);
}

/// q̈ = M⁻¹ (τ − bias). Returns false when M is not positive definite; the caller then
/// solves with a pivoting LDLT from s.mass_matrix (lower triangle) and s.bias.
template <int N, class Storage, class Output>
[[gnu::always_inline]] inline bool complete_forward_dynamics(const RobotModel& model, const Parameters& parameters,
                                      const DynamicsWorkspace& w, const double* q, const double* qd,
                                      const double* tau, Storage& s, Output& qdd) {
  const int n = joint_count<N>(model);
  forward_pass<N, false>(model, parameters, w, q, qd, nullptr, s);
  backward_pass<N, false>(model, parameters, nullptr, s, s.bias);
  lower_mass_matrix<N>(model, parameters, s);
  for (int i = 0; i < n; ++i) qdd[i] = tau[i] - s.bias[i];
  return cholesky_solve(n, s.mass_matrix, s.cholesky_factor, qdd);
}

}  // namespace manipid::detail

// log_cholesky.cpp — Rucker & Wensing's log-Cholesky map θ ↔ π and its exact Jacobian.
#include "manipid/core/robot/log_cholesky.h"

#include "robot/inertia_internal.h"
#include "manipid/core/errors.h"
#include "numbers.h"

#include <cmath>
#include <sstream>

namespace manipid::robot {
namespace {

using manipid::detail::short_number;

// Û = U/e^α: upper triangular, unit bottom-right, diagonal e^{d_i}.
Eigen::Matrix4d scaled_factor(const LogCholesky& theta) {
  Eigen::Matrix4d u = Eigen::Matrix4d::Zero();
  u(0, 0) = std::exp(theta[1]);
  u(1, 1) = std::exp(theta[2]);
  u(2, 2) = std::exp(theta[3]);
  u(3, 3) = 1.0;
  u(0, 1) = theta[4];  // s12
  u(1, 2) = theta[5];  // s23
  u(0, 2) = theta[6];  // s13
  u(0, 3) = theta[7];  // t1
  u(1, 3) = theta[8];  // t2
  u(2, 3) = theta[9];  // t3
  return u;
}

// The entry (row, column) of Û that θ_j (j = 1..9) sets, in θ's order.
struct Entry {
  int row, column;
};
constexpr Entry kEntries[10] = {{3, 3},                  // α scales the whole factor, handled apart
                                {0, 0}, {1, 1}, {2, 2},  // d1, d2, d3 (through e^{d_i})
                                {0, 1}, {1, 2}, {0, 2},  // s12, s23, s13
                                {0, 3}, {1, 3}, {2, 3}};  // t1, t2, t3

}  // namespace

Vector10d standard_from_log_cholesky(const LogCholesky& theta, Matrix10d* jacobian) {
  const Eigen::Matrix4d u = scaled_factor(theta);
  const double mass = std::exp(2.0 * theta[0]);  // e^{2α}
  // π = e^{2α}·L(Û Ûᵀ), L the linear map J → π (standard_from_pseudo_inertia).
  const Vector10d link = mass * standard_from_pseudo_inertia(u * u.transpose());
  if (jacobian) {
    jacobian->col(0) = 2.0 * link;
    for (int j = 1; j < 10; ++j) {
      const auto [a, b] = kEntries[j];
      // ∂Û_ab/∂θ_j: e^{d_i} for the diagonal (its own value), 1 for s and t.
      const double v = j <= 3 ? u(a, b) : 1.0;
      // ∂(Û Ûᵀ) = ∂Û Ûᵀ + Û ∂Ûᵀ with ∂Û = v e_a e_bᵀ: v (e_a Û_{:,b}ᵀ + Û_{:,b} e_aᵀ).
      Eigen::Matrix4d d_pseudo = Eigen::Matrix4d::Zero();
      d_pseudo.row(a) += v * u.col(b).transpose();
      d_pseudo.col(a) += v * u.col(b);
      jacobian->col(j) = mass * standard_from_pseudo_inertia(d_pseudo);
    }
  }
  return link;
}

namespace detail {

Eigen::Matrix4d log_cholesky_factor(const Vector10d& theta) { return std::exp(theta[0]) * scaled_factor(theta); }

LogCholeskyStatus try_log_cholesky(const Vector10d& link, Vector10d& theta) {
  const double mass = link[0];
  if (!(mass > 0.0)) return LogCholeskyStatus::mass;
  const Eigen::Matrix4d pseudo = pseudo_inertia(link);
  const Eigen::Vector3d com = link.segment<3>(1) / mass;  // t = c
  // S Sᵀ = Σ_c/m = (Σ − h cᵀ)/m, the second moment about the centre of mass per unit mass (m²).
  const Eigen::Matrix3d shape = (pseudo.topLeftCorner<3, 3>() - link.segment<3>(1) * com.transpose()) / mass;
  if (!shape.allFinite()) return LogCholeskyStatus::centre_of_mass;
  // Upper-triangular S with S Sᵀ = shape: Cholesky from the bottom-right corner. Each pivot
  // is a conditional variance (z; y given z; x given y and z), positive exactly when J ≻ 0.
  const double pivot3 = shape(2, 2);
  if (!(pivot3 > 0.0)) return LogCholeskyStatus::pivot_z;
  const double s33 = std::sqrt(pivot3);
  const double s23 = shape(1, 2) / s33;
  const double s13 = shape(0, 2) / s33;
  const double pivot2 = shape(1, 1) - s23 * s23;
  if (!(pivot2 > 0.0)) return LogCholeskyStatus::pivot_y;
  const double s22 = std::sqrt(pivot2);
  const double s12 = (shape(0, 1) - s13 * s23) / s22;
  const double pivot1 = shape(0, 0) - s12 * s12 - s13 * s13;
  if (!(pivot1 > 0.0)) return LogCholeskyStatus::pivot_x;
  const double s11 = std::sqrt(pivot1);
  theta << 0.5 * std::log(mass), std::log(s11), std::log(s22), std::log(s33), s12, s23, s13, com;
  return LogCholeskyStatus::ok;
}

}  // namespace detail

LogCholesky log_cholesky_from_standard(const Vector10d& link, const std::string& field) {
  if (!link.allFinite()) throw InputError(field, field + ": the inertial parameters are not all finite numbers");
  LogCholesky theta;
  const char* pivot = nullptr;
  switch (detail::try_log_cholesky(link, theta)) {
    case detail::LogCholeskyStatus::ok:
      return theta;
    case detail::LogCholeskyStatus::mass:
      throw InputError(field, field + ": the mass is not positive (" + short_number(link[0]) +
                                  " kg), so the link has no log-Cholesky coordinates; project it first");
    case detail::LogCholeskyStatus::centre_of_mass:
      throw InputError(field, field + ": the centre of mass h/m is not a finite number (mass " + short_number(link[0]) +
                                  " kg)");
    case detail::LogCholeskyStatus::pivot_z: pivot = "z"; break;
    case detail::LogCholeskyStatus::pivot_y: pivot = "y given z"; break;
    case detail::LogCholeskyStatus::pivot_x: pivot = "x given y and z"; break;
  }
  throw InputError(field, field + ": the pseudo-inertia is not positive definite (the second moment about the centre "
                                  "of mass has no positive variance along " +
                                  std::string(pivot) + "); project the link first");
}

}  // namespace manipid::robot

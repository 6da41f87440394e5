// inertia_internal.h — internal: exception-free projection and log-Cholesky inverse, the factor U, the length scale.
#pragma once

#include "manipid/core/robot/consistency.h"

#include <optional>

namespace manipid::robot::detail {

/// The radius of gyration of a link about its origin, √(|tr Σ| / |m|) (m), or 1 m when that
/// is not a positive finite number (a massless or shapeless link has no size of its own).
double link_length_scale(const Vector10d& link);

/// project_link() for finite input and valid settings (the caller checked both): nullopt when
/// the scaled pseudo-inertia has no positive eigenvalue, so there is nothing to keep.
std::optional<LinkProjection> try_project_link(const Vector10d& link, double length_scale, double relative_floor);

/// Why π → θ failed, or `ok`.
enum class LogCholeskyStatus { ok, mass, centre_of_mass, pivot_z, pivot_y, pivot_x };

/// log_cholesky_from_standard() for finite input without exceptions: writes θ when it returns ok.
LogCholeskyStatus try_log_cholesky(const Vector10d& link, Vector10d& theta);

/// U = e^α Û, the upper-triangular factor of J = U Uᵀ (log_cholesky.h).
Eigen::Matrix4d log_cholesky_factor(const Vector10d& theta);

}  // namespace manipid::robot::detail

// log_cholesky.h — Rucker & Wensing's smooth, unconstrained coordinates of a physically consistent rigid body.
//
// C. Rucker and P. M. Wensing, "Smooth Parameterization of Rigid-Body Inertia", IEEE RA-L 7(2),
// 2022. Every θ ∈ R¹⁰ gives a pseudo-inertia J = U Uᵀ ≻ 0 through the upper-triangular
//
//          ⎡ e^{d1}  s12     s13     t1 ⎤
//   U = e^α⎢ 0       e^{d2}  s23     t2 ⎥      θ = (α, d1, d2, d3, s12, s23, s13, t1, t2, t3)
//          ⎢ 0       0       e^{d3}  t3 ⎥      (the paper's order, also Pinocchio's)
//          ⎣ 0       0       0       1  ⎦
//
// and every J ≻ 0 comes from exactly one θ. Reading J = U Uᵀ block by block:
//
//   m = e^{2α},   h = e^{2α}·t   (so t = c, the centre of mass, m),
//   Σ = e^{2α}(S Sᵀ + t tᵀ),     S = the upper-left 3×3 of U/e^α,
//
// so S Sᵀ = Σ_c/m is the second moment about the centre of mass per unit mass (m²): α sets
// the mass, t the centre of mass, (d, s) the shape. Written out (Σ̂ = Σ/m):
//
//   Σ̂11 = e^{2d1} + s12² + s13² + t1²      Σ̂12 = s12·e^{d2} + s13·s23 + t1·t2
//   Σ̂22 = e^{2d2} + s23² + t2²             Σ̂13 = s13·e^{d3} + t1·t3
//   Σ̂33 = e^{2d3} + t3²                    Σ̂23 = s23·e^{d3} + t2·t3
//
//   π = e^{2α}·(1, t1, t2, t3, Σ̂22+Σ̂33, −Σ̂12, −Σ̂13, Σ̂11+Σ̂33, −Σ̂23, Σ̂11+Σ̂22).
//
// Units: α and d are logarithms (of √(m/kg) and of a length in m); s and t are lengths in m.
#pragma once

#include "manipid/core/robot/consistency.h"

#include <string>

namespace manipid::robot {

/// θ = (α, d1, d2, d3, s12, s23, s13, t1, t2, t3), see the file comment.
using LogCholesky = Vector10d;

/// \brief θ → π: the standard parameters (always physically consistent) of a log-Cholesky vector.
/// \param[in] theta  log-Cholesky coordinates
/// \param[out] jacobian  when not null, the exact ∂π/∂θ (10×10, row i = π_i, column j = θ_j):
///   ∂π/∂α = 2π; for the other coordinates, with Û = U/e^α and θ_j the entry Û_ab
///   (e^{d_i} for d_i), ∂Ĵ/∂θ_j = v(e_a Û_{:,b}ᵀ + Û_{:,b} e_aᵀ), v = ∂Û_ab/∂θ_j, and
///   ∂π/∂θ_j = e^{2α}·standard_from_pseudo_inertia(∂Ĵ/∂θ_j) (the map J → π is linear).
/// Overflows to ±Inf (never NaN from this function) for |θ| beyond ~350; callers that step θ
/// check the result.
Vector10d standard_from_log_cholesky(const LogCholesky& theta, Matrix10d* jacobian = nullptr);

/// \brief π → θ for a link whose pseudo-inertia is positive definite.
///
/// α = ½ ln m, t = h/m, and (d, s) from the upper-triangular factor of Σ_c/m = S Sᵀ
/// (Cholesky from the bottom-right corner). Throws InputError(`field`) when π has a non-finite
/// entry or J is not positive definite (say which: mass, or which pivot of Σ_c); project it
/// first with project_link().
LogCholesky log_cholesky_from_standard(const Vector10d& link, const std::string& field = "link");

}  // namespace manipid::robot

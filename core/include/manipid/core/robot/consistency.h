// consistency.h — is a vector of rigid-body parameter estimates physically possible, and the nearest one that is.
//
// Conventions (shared with the regressor τ = Y(q, q̇, q̈)·π): each link contributes ten
// standard parameters, in its own frame, about its origin O, in this order
//
//     π_link = (m, mx, my, mz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz)
//              kg  kg·m (h = m·c)   kg·m² (tensor entries about O, not negated products)
//
// The pseudo-inertia (Wensing, Kim & Slotine, "Linear matrix inequalities for physically
// consistent inertial parameter identification", IEEE RA-L 2017) is the second-moment matrix
// of the link's mass density ρ,
//
//     J = ∫ [x; 1][x; 1]ᵀ ρ(x) dx = [ Σ   h ]      Σ = ½ tr(I_O)·E − I_O   (kg·m²)
//                                   [ hᵀ  m ],
//
// and π is realisable by a density on R³ exactly when J ≻ 0. Equivalent, and reported one
// by one because each names a different mistake: m > 0; the inertia about the centre of
// mass I_c = I_O − m(‖c‖²E − c cᵀ) positive definite; its principal moments obeying the
// strict triangle inequalities (the eigenvalues of Σ_c = ½tr(I_c)E − I_c are
// ½(λj + λk − λi), and J ≻ 0 ⇔ m > 0 ∧ Σ_c ≻ 0 by the Schur complement).
//
// Friction and rotor parameters (viscous fv ≥ 0, Coulomb fc ≥ 0, rotor inertia Ia ≥ 0,
// offset fo of either sign) live elsewhere in π; ParameterStructure says where.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

namespace manipid::robot {

/// One link's ten standard parameters (m, mx, my, mz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz): kg, kg·m, kg·m².
using Vector10d = Eigen::Matrix<double, 10, 1>;
using Matrix10d = Eigen::Matrix<double, 10, 10>;

/// Where things are in the parameter vector π (size `parameter_count`).
///
/// Each link occupies ten consecutive entries starting at its offset, in the order above.
/// Entries listed in `non_negative` (viscous and Coulomb friction, rotor inertia) must be
/// ≥ 0. Every other entry (friction offsets, anything else) is free. Blocks must not overlap
/// each other or a non-negative entry. Names are the caller's (URDF link names, the
/// regressor's parameter names); this module never invents one.
struct ParameterStructure {
  int parameter_count = 0;                   ///< p, the size of π
  std::vector<int> link_offsets;             ///< index of each link's `m`; ten entries each
  std::vector<int> non_negative;             ///< indices that must be ≥ 0 (fv, fc, Ia)
  std::vector<std::string> link_names;       ///< one per link, same order as link_offsets
  std::vector<std::string> parameter_names;  ///< p names, one per entry of π

  int link_count() const { return static_cast<int>(link_offsets.size()); }
};

/// Throws manipid::InputError naming the field ("structure.link_offsets", ...) unless the
/// structure is usable: p > 0, blocks inside [0, p) and disjoint, non-negative indices inside
/// [0, p), outside every block and not repeated, one name per link and per parameter.
void check_structure(const ParameterStructure& structure);

/// \brief The pseudo-inertia J (4×4, symmetric) of one link's standard parameters.
/// Units: Σ block kg·m², h column kg·m, m kg.
Eigen::Matrix4d pseudo_inertia(const Vector10d& link);

/// \brief The standard parameters of a pseudo-inertia (the inverse of pseudo_inertia()):
/// m = J₃₃, h = J₀:₃,₃, I_O = tr(Σ)E − Σ. Only the upper triangle of J is read.
Vector10d standard_from_pseudo_inertia(const Eigen::Matrix4d& pseudo);

/// Relative size below which a computed eigenvalue (or margin) counts as zero: rounding in
/// the subtraction I_O − m(‖c‖²E − c cᵀ) and in a symmetric eigensolver is a few ε·‖input‖
/// (ε = 2.2e-16); 1e-12 leaves a margin of four orders above that and is still far below
/// any real body (it would be a link a million times thinner than it is long).
inline constexpr double kConsistencyRelativeTolerance = 1e-12;

/// Every condition of one link, with the numbers behind each verdict.
struct LinkConsistency {
  std::string name;
  double mass = 0.0;  ///< kg
  /// Centre of mass c = h/m, m. NaN when m ≤ 0 (as are the next four fields).
  Eigen::Vector3d centre_of_mass;
  Eigen::Matrix3d inertia_about_com;   ///< I_c, kg·m²
  Eigen::Vector3d principal_moments;   ///< eigenvalues of I_c, ascending, kg·m²
  /// min over i of (λj + λk − λi) for the principal moments: > 0 for a solid body, 0 for a
  /// flat one (lamina), < 0 for none. kg·m².
  double triangle_margin = 0.0;
  /// Eigenvalues of J, ascending. J's entries mix kg, kg·m and kg·m², so their sizes depend on
  /// the units and only their signs are intrinsic (Sylvester's law of inertia).
  Eigen::Vector4d pseudo_inertia_eigenvalues;

  bool mass_positive = false;
  bool inertia_about_com_positive_definite = false;
  bool triangle_inequalities = false;
  /// J ≻ 0: decided as m > 0 ∧ Σ_c ≻ 0 (the Schur complement, in kg·m² alone, so the
  /// tolerance means the same thing for any link), hence consistent with the two above.
  bool pseudo_inertia_positive_definite = false;

  /// All four hold (they are equivalent to the last one; each is reported for its message).
  bool consistent() const {
    return mass_positive && inertia_about_com_positive_definite && triangle_inequalities &&
           pseudo_inertia_positive_definite;
  }
};

/// One parameter that must be ≥ 0.
struct NonNegativeCheck {
  std::string name;
  int index = 0;        ///< in π
  double value = 0.0;   ///< its unit is the caller's (N·m·s/rad, N·m, kg·m², ...)
  bool ok = false;      ///< value ≥ 0
};

/// The verdict on a whole parameter vector.
struct ConsistencyReport {
  std::vector<LinkConsistency> links;           ///< in structure order
  std::vector<NonNegativeCheck> non_negative;   ///< in structure order
  /// One plain sentence per violated condition, naming the link or parameter, e.g.
  /// "link3: the inertia about the centre of mass is not positive definite (smallest
  /// eigenvalue -0.012 kg·m²)". Empty when consistent.
  std::vector<std::string> findings;

  bool consistent() const;
  /// Indices (into `links`) of the links that are not consistent.
  std::vector<int> inconsistent_links() const;
};

/// \brief Checks one link. Throws InputError(`name`) when an entry is not finite.
/// \param[in] link  ten standard parameters (kg, kg·m, kg·m²)
/// \param[in] name  the link's name, used in the findings
/// \param[out] findings  sentences appended for each violated condition (may be null)
LinkConsistency check_link(const Vector10d& link, const std::string& name,
                           std::vector<std::string>* findings = nullptr);

/// \brief Checks every link and every non-negative parameter of π (size structure.parameter_count).
/// Throws InputError("structure....") for an unusable structure, InputError("pi") when π has
/// the wrong size or a non-finite entry.
ConsistencyReport check_consistency(const ParameterStructure& structure, const Eigen::VectorXd& pi);

/// How an inconsistent link is moved onto the consistent set.
struct ProjectionOptions {
  /// Length L (m) that makes J's entries commensurate: the projection works on
  /// J̃ = D J D, D = diag(1/L, 1/L, 1/L, 1), whose entries are all in kg. 0 = the link's own
  /// radius of gyration about its origin, L² = |tr Σ| / |m| (tr Σ = ½ tr I_O), or 1 m when
  /// that is not a positive finite number. With that L, tr(Σ̃) = m: mass and shape weigh
  /// alike in the distance, instead of whichever has the larger number in SI units.
  double length_scale = 0.0;
  /// Smallest eigenvalue kept in J̃, relative to J̃'s largest (kg), in (0, 1). With L the
  /// radius of gyration, J̃'s largest eigenvalue is about m to 2m and the eigenvalues of the
  /// shape block are about m·(r_i/L)² for the principal radii of gyration r_i about the
  /// centre of mass, so 1e-6 keeps every r_i above about 1e-3 of the link's size: a link may
  /// become thin, never flat. Far above kConsistencyRelativeTolerance (the result passes
  /// check_link) and far below the size of a real body (the result stays close). Relative
  /// to the largest eigenvalue, which clipping leaves alone, so projecting twice with the
  /// same L changes nothing the second time beyond rounding.
  double relative_floor = 1e-6;
};

/// The outcome of projecting one link.
struct LinkProjection {
  Vector10d link;          ///< the projected standard parameters
  /// false: every eigenvalue of the input's J̃ was already above the floor (returned unchanged)
  bool changed = false;
  double distance = 0.0;   ///< ‖J̃_projected − J̃‖_F, kg
  double length_scale = 0.0;  ///< the L used, m
};

/// \brief The nearest link whose scaled pseudo-inertia has every eigenvalue ≥ the floor.
///
/// J̃ = V Λ Vᵀ → V max(Λ, floor) Vᵀ: the nearest matrix in the Frobenius norm with that
/// spectral bound (Higham 1988), mapped back through D⁻¹. Throws InputError(`field`) when an
/// entry is not finite, when the options are out of range, or when J̃ has no positive
/// eigenvalue at all (nothing physical is left to keep: use a prior value instead).
LinkProjection project_link(const Vector10d& link, const ProjectionOptions& options = {},
                            const std::string& field = "link");

}  // namespace manipid::robot

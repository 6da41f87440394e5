// consistency.cpp — consistency checks of standard parameters and the projection onto the consistent set.
#include "manipid/core/robot/consistency.h"

#include "robot/inertia_internal.h"
#include "manipid/core/errors.h"
#include "numbers.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace manipid::robot {
namespace {

using manipid::detail::kNaN;
using manipid::detail::short_number;

// I_O as a matrix from π's six inertia entries (Ixx, Ixy, Ixz, Iyy, Iyz, Izz).
Eigen::Matrix3d inertia_matrix(const Vector10d& link) {
  Eigen::Matrix3d inertia;
  inertia << link[4], link[5], link[6],  //
      link[5], link[7], link[8],         //
      link[6], link[8], link[9];
  return inertia;
}

}  // namespace

void check_structure(const ParameterStructure& structure) {
  const int p = structure.parameter_count;
  if (p <= 0) {
    throw InputError("structure.parameter_count", "the parameter vector must have at least one entry, got " +
                                                      std::to_string(p));
  }
  // owner[i]: -1 free, k ≥ 0 link k, -2 non-negative entry.
  std::vector<int> owner(static_cast<std::size_t>(p), -1);
  for (int k = 0; k < structure.link_count(); ++k) {
    const int offset = structure.link_offsets[k];
    if (offset < 0 || offset > p - 10) {
      throw InputError("structure.link_offsets", "link " + std::to_string(k) + " starts at " + std::to_string(offset) +
                                                     ": its ten entries must lie inside the " + std::to_string(p) +
                                                     " parameters");
    }
    for (int i = offset; i < offset + 10; ++i) {
      if (owner[i] != -1) {
        throw InputError("structure.link_offsets", "links " + std::to_string(owner[i]) + " and " + std::to_string(k) +
                                                       " overlap at parameter " + std::to_string(i));
      }
      owner[i] = k;
    }
  }
  for (int index : structure.non_negative) {
    if (index < 0 || index >= p) {
      throw InputError("structure.non_negative", "index " + std::to_string(index) + " is outside the " +
                                                     std::to_string(p) + " parameters");
    }
    if (owner[index] >= 0) {
      throw InputError("structure.non_negative", "index " + std::to_string(index) + " lies inside link " +
                                                     std::to_string(owner[index]) +
                                                     "'s block: links are constrained as a whole");
    }
    if (owner[index] == -2) {
      throw InputError("structure.non_negative", "index " + std::to_string(index) + " is listed twice");
    }
    owner[index] = -2;
  }
  if (static_cast<int>(structure.link_names.size()) != structure.link_count()) {
    throw InputError("structure.link_names", "expected one name per link (" + std::to_string(structure.link_count()) +
                                                 "), got " + std::to_string(structure.link_names.size()));
  }
  if (static_cast<int>(structure.parameter_names.size()) != p) {
    throw InputError("structure.parameter_names", "expected one name per parameter (" + std::to_string(p) + "), got " +
                                                      std::to_string(structure.parameter_names.size()));
  }
}

Eigen::Matrix4d pseudo_inertia(const Vector10d& link) {
  const Eigen::Matrix3d inertia = inertia_matrix(link);
  Eigen::Matrix4d pseudo;
  pseudo.topLeftCorner<3, 3>() = 0.5 * inertia.trace() * Eigen::Matrix3d::Identity() - inertia;
  pseudo.topRightCorner<3, 1>() = link.segment<3>(1);
  pseudo.bottomLeftCorner<1, 3>() = link.segment<3>(1).transpose();
  pseudo(3, 3) = link[0];
  return pseudo;
}

Vector10d standard_from_pseudo_inertia(const Eigen::Matrix4d& pseudo) {
  // Σ from the upper triangle; I_O = tr(Σ)E − Σ (tr I_O = 2 tr Σ, so this inverts Σ = ½tr(I_O)E − I_O).
  const double trace = pseudo(0, 0) + pseudo(1, 1) + pseudo(2, 2);
  Vector10d link;
  link << pseudo(3, 3), pseudo(0, 3), pseudo(1, 3), pseudo(2, 3),  //
      trace - pseudo(0, 0), -pseudo(0, 1), -pseudo(0, 2),           //
      trace - pseudo(1, 1), -pseudo(1, 2),                          //
      trace - pseudo(2, 2);
  return link;
}

bool ConsistencyReport::consistent() const {
  return std::all_of(links.begin(), links.end(), [](const LinkConsistency& link) { return link.consistent(); }) &&
         std::all_of(non_negative.begin(), non_negative.end(), [](const NonNegativeCheck& check) { return check.ok; });
}

std::vector<int> ConsistencyReport::inconsistent_links() const {
  std::vector<int> indices;
  for (std::size_t k = 0; k < links.size(); ++k) {
    if (!links[k].consistent()) indices.push_back(static_cast<int>(k));
  }
  return indices;
}

LinkConsistency check_link(const Vector10d& link, const std::string& name, std::vector<std::string>* findings) {
  if (!link.allFinite()) throw InputError(name, name + ": the inertial parameters are not all finite numbers");
  auto say = [&](const std::string& sentence) {
    if (findings) findings->push_back(name + ": " + sentence);
  };

  LinkConsistency result;
  result.name = name;
  result.mass = link[0];
  result.centre_of_mass.setConstant(kNaN);
  result.inertia_about_com.setConstant(kNaN);
  result.principal_moments.setConstant(kNaN);
  result.triangle_margin = kNaN;
  result.pseudo_inertia_eigenvalues.setConstant(kNaN);

  // Nothing non-finite reaches an eigensolver (Eigen 3.4's SelfAdjointEigenSolver reads out of
  // bounds on NaN): entries near the overflow limit can still make ½tr(I_O) infinite.
  const Eigen::Matrix4d pseudo = pseudo_inertia(link);
  if (!pseudo.allFinite()) {
    throw InputError(name, name + ": the inertial parameters are too large to evaluate (the pseudo-inertia overflows)");
  }
  result.pseudo_inertia_eigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(pseudo, Eigen::EigenvaluesOnly).eigenvalues();

  const double mass = link[0];
  result.mass_positive = mass > 0.0;
  if (!result.mass_positive) {
    say("the mass is not positive (" + short_number(mass) + " kg)");
  } else {
    const Eigen::Vector3d com = link.segment<3>(1) / mass;
    const Eigen::Matrix3d inertia = inertia_matrix(link);
    const Eigen::Matrix3d parallel = mass * (com.squaredNorm() * Eigen::Matrix3d::Identity() - com * com.transpose());
    const Eigen::Matrix3d about_com = inertia - parallel;
    if (!about_com.allFinite()) {
      // A mass so small against h that c = h/m overflows: no centre of mass to speak of.
      say("the centre of mass h/m is not a finite number (mass " + short_number(mass) + " kg)");
    } else {
      result.centre_of_mass = com;
      result.inertia_about_com = about_com;
      result.principal_moments =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(about_com, Eigen::EigenvaluesOnly).eigenvalues();
      const Eigen::Vector3d& moments = result.principal_moments;  // ascending
      // Rounding: I_c is a difference of I_O and the parallel-axis term, so its error is a few
      // ε times their size, not ε times its own.
      const double tolerance = kConsistencyRelativeTolerance * (inertia.norm() + parallel.norm());
      result.inertia_about_com_positive_definite = moments[0] > tolerance;
      // The only inequality that can fail is the largest moment against the other two.
      result.triangle_margin = moments[0] + moments[1] - moments[2];
      result.triangle_inequalities = result.triangle_margin > tolerance;
      // Σ_c = ½tr(I_c)E − I_c has eigenvalues ½(λj + λk − λi): J ≻ 0 ⇔ m > 0 ∧ margin > 0.
      result.pseudo_inertia_positive_definite = result.triangle_inequalities;

      if (!result.inertia_about_com_positive_definite) {
        say("the inertia about the centre of mass is not positive definite (smallest eigenvalue " +
            short_number(moments[0]) + " kg·m²)");
      }
      if (!result.triangle_inequalities) {
        const std::string moments_text =
            "(" + short_number(moments[0]) + ", " + short_number(moments[1]) + ", " + short_number(moments[2]) + " kg·m²)";
        if (result.triangle_margin < -tolerance) {
          say("the principal moments of inertia about the centre of mass " + moments_text +
              " violate the triangle inequality: the largest exceeds the sum of the other two by " +
              short_number(-result.triangle_margin) + " kg·m²");
        } else {
          say("the principal moments of inertia about the centre of mass " + moments_text +
              " meet the triangle inequality only with equality: a body with no thickness");
        }
      }
    }
  }
  if (!result.pseudo_inertia_positive_definite) {
    say("the pseudo-inertia is not positive definite (smallest eigenvalue " +
        short_number(result.pseudo_inertia_eigenvalues[0]) + "): no distribution of mass has these parameters");
  }
  return result;
}

ConsistencyReport check_consistency(const ParameterStructure& structure, const Eigen::VectorXd& pi) {
  check_structure(structure);
  if (pi.size() != structure.parameter_count) {
    throw InputError("pi", "expected " + std::to_string(structure.parameter_count) + " parameters, got " +
                               std::to_string(pi.size()));
  }
  for (Eigen::Index i = 0; i < pi.size(); ++i) {
    if (!std::isfinite(pi[i])) throw InputError("pi", structure.parameter_names[i] + " is not a finite number");
  }
  ConsistencyReport report;
  for (int k = 0; k < structure.link_count(); ++k) {
    report.links.push_back(check_link(pi.segment<10>(structure.link_offsets[k]), structure.link_names[k],
                                      &report.findings));
  }
  for (int index : structure.non_negative) {
    NonNegativeCheck check;
    check.name = structure.parameter_names[index];
    check.index = index;
    check.value = pi[index];
    check.ok = pi[index] >= 0.0;
    if (!check.ok) report.findings.push_back(check.name + ": must not be negative, is " + short_number(check.value));
    report.non_negative.push_back(check);
  }
  return report;
}

namespace detail {

double link_length_scale(const Vector10d& link) {
  const double trace_sigma = 0.5 * (link[4] + link[7] + link[9]);  // tr Σ = ½ tr I_O
  const double length = std::sqrt(std::abs(trace_sigma) / std::abs(link[0]));
  return std::isfinite(length) && length > 0.0 ? length : 1.0;
}

std::optional<LinkProjection> try_project_link(const Vector10d& link, double length_scale, double relative_floor) {
  // J̃ = D J D with D = diag(1/L, 1/L, 1/L, 1): every entry in kg, so "nearest" does not depend
  // on whether lengths are in metres or millimetres.
  const Eigen::Vector4d d(1.0 / length_scale, 1.0 / length_scale, 1.0 / length_scale, 1.0);
  const Eigen::Matrix4d scaled = d.asDiagonal() * pseudo_inertia(link) * d.asDiagonal();
  if (!scaled.allFinite()) return std::nullopt;  // never hand a non-finite matrix to the eigensolver
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eigen(scaled);
  const Eigen::Vector4d& values = eigen.eigenvalues();  // ascending
  if (!(values[3] > 0.0)) return std::nullopt;
  const double floor = relative_floor * values[3];

  LinkProjection result;
  result.length_scale = length_scale;
  if (values[0] >= floor) {
    result.link = link;  // already inside: returned bit for bit
    return result;
  }
  const Eigen::Vector4d clipped = values.cwiseMax(floor);
  const Eigen::Matrix4d projected = eigen.eigenvectors() * clipped.asDiagonal() * eigen.eigenvectors().transpose();
  const Eigen::Vector4d undo = d.cwiseInverse();
  result.link = standard_from_pseudo_inertia(undo.asDiagonal() * projected * undo.asDiagonal());
  result.changed = true;
  result.distance = (clipped - values).norm();  // ‖V(Λ' − Λ)Vᵀ‖_F
  return result;
}

}  // namespace detail

LinkProjection project_link(const Vector10d& link, const ProjectionOptions& options, const std::string& field) {
  if (!link.allFinite()) throw InputError(field, field + ": the inertial parameters are not all finite numbers");
  if (!std::isfinite(options.length_scale) || options.length_scale < 0.0) {
    throw InputError("projection.length_scale",
                     "the length scale must be a finite number ≥ 0 m (0: the link's own), got " +
                         short_number(options.length_scale));
  }
  if (!(options.relative_floor > 0.0 && options.relative_floor < 1.0)) {
    throw InputError("projection.relative_floor", "the relative eigenvalue floor must lie in (0, 1), got " +
                                                      short_number(options.relative_floor));
  }
  const double length = options.length_scale > 0.0 ? options.length_scale : detail::link_length_scale(link);
  const std::optional<LinkProjection> result = detail::try_project_link(link, length, options.relative_floor);
  if (!result) {
    throw InputError(field, field + ": the pseudo-inertia has no positive eigenvalue, so no consistent link is near "
                                    "it; use a prior value for this link instead");
  }
  return *result;
}

}  // namespace manipid::robot

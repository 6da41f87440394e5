// link_table.h — an identified robot link by link, in the terms a URDF holds it (mass, centre of mass,
// inertia about it), with what the data determine of each: the table the CLI prints, the JSON carries and
// the dashboard draws beside the base parameters.
//
// "Determined" is decided per standard parameter: π_j is determined when e_j lies in the span of the rows
// of the base combination K (β = K π) that the data see (a finite standard error) — then π_j is a fixed
// combination of base parameters the data estimate. Otherwise the data see π_j only in combinations with
// others (it moves with them, and where they are silent it stays at the prior's value: the URDF's, as
// IdentificationResult::point says), or not at all. (How far a ridge pulled the estimates toward the URDF
// is the base parameters' data share, a separate matter.)
// A link's mass is determined with m; its centre of mass c = h/m with m, mx, my, mz; its inertia about
// the centre of mass I_c = I_O − m(‖c‖²E − c cᵀ) with all ten.
#pragma once

#include "manipid/core/robot/identification.h"
#include "manipid/core/robot/model.h"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace manipid::robot {

struct LinkRow {
  std::string link;                  ///< the body's link (its joint's child) in the URDF
  double mass = 0.0;                 ///< kg
  Eigen::Vector3d centre_of_mass;    ///< m, in the link's frame; NaN when mass ≤ 0
  Eigen::Matrix3d inertia_about_com; ///< kg·m², in the link's axes (URDF ixx … izz); NaN when mass ≤ 0
  bool consistent = false;           ///< a real rigid body (robot/consistency.h)
  /// Per standard parameter (m, mx, my, mz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz): determined by the data.
  std::array<bool, 10> determined{};

  bool mass_determined() const { return determined[0]; }
  bool centre_of_mass_determined() const { return determined[0] && determined[1] && determined[2] && determined[3]; }
  bool inertia_determined() const;
};

/// The links of `result.point`, in joint order.
std::vector<LinkRow> link_table(const Model& model, const IdentificationResult& result);

}  // namespace manipid::robot

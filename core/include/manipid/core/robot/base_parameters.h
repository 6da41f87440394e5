// base_parameters.h — the combinations of standard parameters that a robot's torques determine.
//
// τ = Y(q, q̇, q̈) π is linear in the standard parameters π (robot/parameters.h), but Y never has full
// column rank: some parameters never enter the torque (the mass of a body on a vertical first axis),
// others enter only in fixed combinations (link k's Izz with link k+1's mass times an offset squared).
// The base parameters β = C π are a largest set of independent combinations; τ = Y_b β exactly, where
// Y_b are the columns of Y for the independent parameters (every other column is a fixed linear
// combination of them, for every motion).
//
// They are found from the structure, not from one experiment's data: Y at a few hundred random states
// (q within the joint limits, q̇ and q̈ standard normal; a fixed seed, so the same robot always gives
// the same base), then, in π's order, a standard parameter is independent when its column, scaled to unit
// norm, keeps more than `tolerance` of its norm outside the span of the columns kept before it (modified
// Gram–Schmidt, twice). Columns that are zero for every motion (norm ≤ 1e-10 per row) are set aside first:
// rescaled to unit norm, round-off would pass for an extra rank. Dependent parameters are regrouped into
// the independent ones: β_i = π_{independent_i} + Σ_d K_{i,d} π_{dependent_d}, the coefficients K from
// least squares on the unscaled columns, through the Gram–Schmidt factors Y_indep = Q R (exact to
// round-off; |K| ≤ 1e-9 of the largest is set to 0).
// Scanning in π's order keeps the earlier bodies' parameters and regroups later ones into them, as
// Gautier & Khalil's symbolic regrouping does (for a 7-joint arm: Izz1 absorbs the parameters body 2's
// rotation hides).
#pragma once

#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"

#include <Eigen/Core>

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

namespace manipid::robot {

struct BaseParameterOptions {
  /// Random states stacked; 0 = enough for twice as many rows as standard parameters (at least 100).
  int random_states = 0;
  /// A unit-norm column with less than this fraction of its norm outside the span of the columns kept
  /// before it is dependent. Dependent columns measure ~1e-15 here, independent ones of a well-posed
  /// robot ≥ 1e-4; 1e-8 sits between with six orders of room on each side.
  double tolerance = 1e-8;
  std::uint64_t seed = 1;
  /// Checked once per column (O(n³) in all: 2.4 s for 50 joints): when set, Interrupted is thrown.
  const std::atomic<bool>* cancel = nullptr;
};

struct BaseParameters {
  int standard_count = 0;             ///< dim π
  std::vector<int> independent;       ///< standard indices that name the base parameters, ascending
  std::vector<int> dependent;         ///< standard indices regrouped into them, ascending
  std::vector<int> absent;            ///< standard indices that never enter the torque, ascending
  /// β = combination · π: base count × dim π; row i has 1 at independent[i] and K_{i,d} at dependent[d].
  Eigen::MatrixXd combination;
  /// Row i as text: "Izz1 + Iyy2 + 0.1089*m2 - 0.66*mz2" (coefficients to 6 significant digits).
  std::vector<std::string> names;

  int size() const { return static_cast<int>(independent.size()); }
};

/// The base parameters of `model` with the layout's friction and armature blocks (see the file comment).
/// Throws InputError("random_states"/"tolerance") for bad options, Interrupted when options.cancel is set.
BaseParameters base_parameters(const Model& model, const ParameterLayout& layout, const BaseParameterOptions& options = {});

}  // namespace manipid::robot

// least_squares.h — internal: Levenberg–Marquardt for costs of the form |r(θ)|² + c, the "LM" algorithm.
//
// minimize() (optimizer.h) dispatches here when the algorithm is "LM"; everything the NLopt path
// guarantees holds here too: fixed parameters stay fixed, bounds hold (a step is projected onto
// them, and a parameter on a bound that the gradient pushes outward is held for that step),
// every evaluation is recorded in the EvaluationLog, cancel is checked at every evaluation, and
// max_evaluations and max_seconds are budgets. Parameters are scaled by their start values, and
// the Jacobian's columns by their norms (Marquardt's scaling, the largest seen so far, as in
// MINPACK), so kg and m look alike. Each step solves the damped normal equations through an SVD
// of the scaled Jacobian: a direction the data cannot see (a zero singular value, m1/l1 of the
// paper's robot) gets no step rather than a huge one. The iteration — Nielsen's damping update,
// the acceptance of a step, the stop tests — is core's one minimiser's (gauss_newton.h); this is
// its problem.
#pragma once

#include "estimation/optimizer.h"

namespace manipid::detail {

/// Stops (Summary-style, in words):
///   "converged: relative step below <xtol>"        an accepted step had ‖Δx‖ ≤ xtol (‖x‖ + xtol), x the
///                                                   scaled parameters;
///   "converged: relative cost change below <ftol>" an accepted step lowered the cost by ≤ ftol of it;
///   "converged: gradient zero"                      no free parameter can move the cost;
///   "converged: no step lowers the cost in double precision"  the damping ran past its limit;
///   "maxeval_reached", "maxtime_reached", "cancelled", "non_finite_start" as on the NLopt path.
MinimizeOutcome minimize_least_squares(const LeastSquaresFunction& function, const Eigen::VectorXd& initial,
                                       const MinimizeSettings& settings);

}  // namespace manipid::detail

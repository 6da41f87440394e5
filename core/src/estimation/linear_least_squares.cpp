// linear_least_squares.cpp — column scaling, QR, SVD, shrinkage toward the prior (estimation/linear_least_squares.h).
#include "manipid/core/estimation/linear_least_squares.h"

#include "manipid/core/errors.h"
#include "manipid/core/estimation/rules.h"

#include <Eigen/QR>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace manipid::estimation {

LinearSolution solve_linear(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::VectorXd>& y,
                            const LinearSolveOptions& options) {
  const Eigen::Index b = A.cols();
  if (A.rows() != y.size() || A.rows() < 1) {
    throw InputError("rows", "the least-squares rows (" + std::to_string(A.rows()) + ") and targets (" +
                                 std::to_string(y.size()) + ") do not match");
  }
  const Eigen::VectorXd prior = options.prior.size() ? options.prior : Eigen::VectorXd::Zero(b);
  if (prior.size() != b || !prior.allFinite()) {
    throw InputError("prior", "the prior needs " + std::to_string(b) + " finite values");
  }
  if (!(options.ridge >= 0.0) || !std::isfinite(options.ridge)) throw InputError("ridge", "the ridge must be >= 0");

  LinearSolution solution;
  solution.scale = A.colwise().norm().transpose();
  const double largest_column = b > 0 ? solution.scale.maxCoeff() : 0.0;
  solution.negligible = Eigen::VectorXi::Zero(b);
  std::vector<Eigen::Index> kept;
  for (Eigen::Index c = 0; c < b; ++c) {
    if (solution.scale[c] > kNegligibleColumn * largest_column) {
      kept.push_back(c);
    } else {
      solution.negligible[c] = 1;
      solution.scale[c] = 1.0;
    }
  }
  const Eigen::Index m = static_cast<Eigen::Index>(kept.size());
  Eigen::MatrixXd As(A.rows(), m);
  for (Eigen::Index j = 0; j < m; ++j) As.col(j) = A.col(kept[static_cast<std::size_t>(j)]) / solution.scale[kept[static_cast<std::size_t>(j)]];
  const Eigen::VectorXd x0 = solution.scale.cwiseProduct(prior);
  // The rows the kept columns must explain: the prior's share of the negligible ones removed.
  Eigen::VectorXd target = y;
  for (Eigen::Index c = 0; c < b; ++c) {
    if (solution.negligible[c]) target -= A.col(c) * prior[c];
  }
  Eigen::VectorXd x0_kept(m);
  for (Eigen::Index j = 0; j < m; ++j) x0_kept[j] = x0[kept[static_cast<std::size_t>(j)]];

  // QR first (rows × m → m × m), then an SVD of the small triangle: the singular values are A_s's.
  Eigen::MatrixXd R;
  Eigen::VectorXd z;
  if (As.rows() >= m) {
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(As);
    R = qr.matrixQR().topRows(m).triangularView<Eigen::Upper>();
    z = (qr.householderQ().transpose() * (target - As * x0_kept)).head(m);
  } else {
    R = As;  // fewer rows than columns: the SVD of the rows themselves
    z = target - As * x0_kept;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeFullU | Eigen::ComputeThinV);
  const Eigen::VectorXd s = svd.singularValues();
  const Eigen::MatrixXd& V_kept = svd.matrixV();
  const Eigen::MatrixXd& U = svd.matrixU();
  const double s1 = s.size() ? s[0] : 0.0;
  const double ridge2 = options.ridge * options.ridge * s1 * s1;

  solution.singular_values = s;
  solution.directions = Eigen::MatrixXd::Zero(b, s.size());
  for (Eigen::Index j = 0; j < m; ++j) solution.directions.row(kept[static_cast<std::size_t>(j)]) = V_kept.row(j);
  solution.data_share = Eigen::VectorXd::Zero(s.size());
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(m);
  Eigen::MatrixXd covariance_scaled = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd share = Eigen::VectorXd::Zero(m);
  for (Eigen::Index k = 0; k < s.size(); ++k) {
    if (!(s[k] > kUnidentifiableRatio * s1)) continue;
    ++solution.determined;
    const double f = s[k] * s[k] / (s[k] * s[k] + ridge2);
    solution.data_share[k] = f;
    const Eigen::VectorXd v = V_kept.col(k);
    dx += v * (f * U.col(k).dot(z) / s[k]);
    covariance_scaled += v * v.transpose() * (f * f / (s[k] * s[k]));
    share += v.cwiseAbs2() * f;
  }
  solution.condition_number = solution.determined == s.size() && solution.determined > 0 && m == b
                                  ? s1 / s[solution.determined - 1]
                                  : std::numeric_limits<double>::infinity();

  Eigen::VectorXd x = x0;
  solution.parameter_share = Eigen::VectorXd::Zero(b);
  solution.covariance_unit = Eigen::MatrixXd::Zero(b, b);
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Index ci = kept[static_cast<std::size_t>(i)];
    x[ci] += dx[i];
    // Σ_k V_ik² f_k with Σ_k V_ik² = 1 lies in [0, 1]; rounding can put it a few ulps above 1.
    solution.parameter_share[ci] = std::clamp(share[i], 0.0, 1.0);
    for (Eigen::Index j = 0; j < m; ++j) {
      const Eigen::Index cj = kept[static_cast<std::size_t>(j)];
      solution.covariance_unit(ci, cj) = covariance_scaled(i, j) / (solution.scale[ci] * solution.scale[cj]);
    }
  }
  solution.estimate = x.cwiseQuotient(solution.scale);
  solution.residual = y - A * solution.estimate;
  return solution;
}

}  // namespace manipid::estimation

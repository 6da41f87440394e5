// link_table.cpp — the identified links as a URDF holds them, and what the data determine (link_table.h).
#include "manipid/core/robot/link_table.h"

#include "manipid/core/robot/consistency.h"

#include <Eigen/QR>

#include <algorithm>
#include <cmath>

namespace manipid::robot {

bool LinkRow::inertia_determined() const {
  return std::all_of(determined.begin(), determined.end(), [](bool d) { return d; });
}

std::vector<LinkRow> link_table(const Model& model, const IdentificationResult& result) {
  const int n = model.joint_count();
  // The rows of K the data see (a finite standard error), and an orthonormal basis Q of their span (in π's
  // space). Not the data share: a ridge the held-out choice found best lowers it without the data seeing less.
  const Eigen::MatrixXd& K = result.base.combination;
  std::vector<Eigen::Index> seen;
  for (Eigen::Index i = 0; i < K.rows(); ++i) {
    if (i < result.std_errors.size() && std::isfinite(result.std_errors[i])) seen.push_back(i);
  }
  Eigen::MatrixXd span(K.cols(), static_cast<Eigen::Index>(seen.size()));
  for (std::size_t c = 0; c < seen.size(); ++c) span.col(static_cast<Eigen::Index>(c)) = K.row(seen[c]).transpose();
  Eigen::MatrixXd basis(K.cols(), 0);
  if (span.cols() > 0) {  // (Eigen's QR of a matrix without columns is not defined)
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(span.rows(), span.cols());
    qr.setThreshold(1e-10);
    qr.compute(span);
    basis = Eigen::MatrixXd(qr.householderQ()).leftCols(qr.rank());
  }
  const Eigen::Index rank = basis.cols();

  std::vector<LinkRow> rows;
  for (int k = 0; k < n; ++k) {
    LinkRow row;
    row.link = model.joints[static_cast<std::size_t>(k)].link;
    const Vector10d link = result.point.segment<10>(10 * k);
    const LinkConsistency check = check_link(link, row.link);
    row.mass = check.mass;
    row.centre_of_mass = check.centre_of_mass;
    row.inertia_about_com = check.inertia_about_com;
    row.consistent = check.consistent();
    for (int j = 0; j < 10; ++j) {
      // e_j in the span: its projection onto the basis is all of it (to rounding).
      const Eigen::Index index = 10 * k + j;
      const double inside = rank > 0 ? basis.row(index).squaredNorm() : 0.0;
      row.determined[static_cast<std::size_t>(j)] = inside > 1.0 - 1e-8;
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace manipid::robot

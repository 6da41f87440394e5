// controller_gains.cpp — PD gains from the filtered control law by least squares (controller_gains.h).
#include "manipid/core/paper/controller_gains.h"

#include "numbers.h"
#include "manipid/core/estimation/rules.h"
#include "manipid/core/signal/filters.h"

#include <Eigen/LU>  // Matrix2d::inverse
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace manipid {
namespace {

void check_shapes(const FilteredData& filtered, const Eigen::MatrixXd& reference) {
  if (reference.rows() != filtered.samples() || reference.cols() != filtered.q.cols() ||
      filtered.tau.rows() != filtered.samples() || filtered.tau.cols() != filtered.q.cols()) {
    throw InputError("ref", "the filtered reference does not match the filtered q and tau");
  }
}

/// RMS of the law's residual over RMS of the torque; 0 when the torque is 0 and the law explains it.
double relative(const Eigen::VectorXd& residual, const Eigen::Ref<const Eigen::VectorXd>& torque) {
  const double scale = detail::rms(torque);
  const double error = detail::rms(residual);
  if (scale > 0) return error / scale;
  return error > 0 ? std::numeric_limits<double>::infinity() : 0.0;
}

}  // namespace

Eigen::MatrixXd filter_reference(const Trajectory& data, const FilterSettings& filter) {
  if (!data.has_reference()) throw InputError("ref", "the data has no ref columns");
  const auto differential = cached_filter(filter);
  const int outputs = differential->checked_output_length(data.samples());
  Eigen::MatrixXd reference(outputs, data.joint_count());
  for (int j = 0; j < data.joint_count(); ++j) {
    differential->apply(FilterOrder::lowpass, data.ref.col(j), reference.col(j));
  }
  return reference;
}

GainFit fit_pd_gains(const FilteredData& filtered, const Eigen::MatrixXd& reference) {
  check_shapes(filtered, reference);
  const int n = static_cast<int>(filtered.q.cols());
  GainFit fit;
  fit.gains.kp.resize(n);
  fit.gains.kd.resize(n);
  fit.relative_residual.resize(n);
  Eigen::MatrixXd columns(filtered.samples(), 2);
  // The residual is low-passed noise: its samples are correlated over about 1/Σc² of them.
  const double correlation = estimation::filtered_residual_factor(
      1, cached_filter(filtered.filter)->coefficients(FilterOrder::lowpass).squaredNorm());
  const double dof = std::max(1.0, static_cast<double>(filtered.samples() - 2));
  for (int j = 0; j < n; ++j) {
    columns.col(0) = reference.col(j) - filtered.q.col(j);  // multiplies Kp
    columns.col(1) = -filtered.qd.col(j);                   // multiplies Kd
    // Column-pivoting QR: a joint that never moves (zero columns) gets zero gains, not NaN.
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(columns);
    const Eigen::Vector2d gains = qr.solve(filtered.tau.col(j));
    fit.gains.kp[j] = std::isfinite(gains[0]) ? gains[0] : 0.0;
    fit.gains.kd[j] = std::isfinite(gains[1]) ? gains[1] : 0.0;
    const Eigen::VectorXd residual = filtered.tau.col(j) - columns * Eigen::Vector2d(fit.gains.kp[j], fit.gains.kd[j]);
    fit.relative_residual[j] = relative(residual, filtered.tau.col(j));
    // A joint whose columns are dependent (it never moves) has no finite covariance: NaN says so.
    const Eigen::Matrix2d information = columns.transpose() * columns;
    const double determinant = information.determinant();
    const bool invertible = std::isfinite(determinant) && determinant > 1e-12 * information(0, 0) * information(1, 1);
    fit.covariance.push_back(invertible ? Eigen::Matrix2d(residual.squaredNorm() / dof * correlation * information.inverse())
                                        : Eigen::Matrix2d::Constant(std::numeric_limits<double>::quiet_NaN()));
  }
  return fit;
}

Eigen::VectorXd pd_law_relative_residual(const FilteredData& filtered, const Eigen::MatrixXd& reference,
                                         const PdController& gains) {
  check_shapes(filtered, reference);
  const int n = static_cast<int>(filtered.q.cols());
  if (gains.kp.size() != n || gains.kd.size() != n) {
    throw InputError("kp", "kp and kd need " + std::to_string(n) + " entries, one per joint");
  }
  Eigen::VectorXd result(n);
  for (int j = 0; j < n; ++j) {
    const Eigen::VectorXd law = gains.kp[j] * (reference.col(j) - filtered.q.col(j)) - gains.kd[j] * filtered.qd.col(j);
    result[j] = relative(filtered.tau.col(j) - law, filtered.tau.col(j));
  }
  return result;
}

}  // namespace manipid

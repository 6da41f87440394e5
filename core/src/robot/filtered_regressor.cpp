// filtered_regressor.cpp — differential filters, regressor, and the regressor's columns low-passed like
// the torque, decimated to the band (robot/filtered_regressor.h).
#include "manipid/core/robot/filtered_regressor.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/regressor.h"
#include "manipid/core/robot/rnea.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace manipid::robot {
namespace {

/// q^f, q̇^f, q̈^f from D (n × N1, one column per filtered sample: sample M + s of the data).
struct FirstPass {
  Eigen::MatrixXd q, qd, qdd;
  int samples = 0;  // N1
};

FirstPass first_pass(const Model& model, const Trajectory& data, const FilterPair& filters,
                     const DifferentialFilter& differentiation) {
  const int n = model.joint_count();
  if (data.joint_count() != n) {
    throw InputError("q", "the data has " + std::to_string(data.joint_count()) + " joints, the robot " +
                              std::to_string(n));
  }
  if (data.samples() < filters.shortest_data()) {
    throw InputError("samples", "the filters (half-lengths M = " + std::to_string(filters.differentiation.half_length) +
                                    " and M_c = " + std::to_string(filters.comparison.half_length) +
                                    ") need at least " + std::to_string(filters.shortest_data()) + " samples; the data has " +
                                    std::to_string(data.samples()) + " (" +
                                    std::to_string(data.t[data.samples() - 1] - data.t[0]) + " s)");
  }
  FirstPass pass;
  pass.samples = differentiation.output_length(data.samples());
  Eigen::VectorXd q(pass.samples), qd(pass.samples), qdd(pass.samples);
  pass.q.resize(n, pass.samples);
  pass.qd.resize(n, pass.samples);
  pass.qdd.resize(n, pass.samples);
  for (int k = 0; k < n; ++k) {
    differentiation.apply_all(data.q.col(k), q, qd, qdd);
    pass.q.row(k) = q.transpose();
    pass.qd.row(k) = qd.transpose();
    pass.qdd.row(k) = qdd.transpose();
  }
  return pass;
}

/// L τ at data samples `centre`, `centre + step`, ... (`count` of them), n columns: only the instants
/// least squares uses, not the whole filtered signal (M_c = 1,000 taps × 20,000 samples × 7 joints
/// would be most of an identification's time).
Eigen::MatrixXd lowpass_at(const Trajectory& data, const DifferentialFilter& comparison, int centre, int step, int count) {
  const int Mc = comparison.settings().half_length;
  const Eigen::VectorXd& taps = comparison.coefficients(FilterOrder::lowpass);
  Eigen::MatrixXd result(count, data.joint_count());
  for (int k = 0; k < data.joint_count(); ++k) {
    for (int r = 0; r < count; ++r) result(r, k) = taps.dot(data.tau.col(k).segment(centre + r * step - Mc, 2 * Mc + 1));
  }
  return result;
}

}  // namespace

FilteredRegressor filtered_regressor(const Model& model, const ParameterLayout& layout, const Trajectory& data,
                                     const FilterPair& filters, const std::atomic<bool>* cancel) {
  filters.differentiation.validate();
  filters.comparison.validate();
  const auto differentiation = cached_filter(filters.differentiation);
  const auto comparison = cached_filter(filters.comparison);
  const FirstPass pass = first_pass(model, data, filters, *differentiation);
  const int n = model.joint_count();
  const int p = layout.size(n);
  const int M = filters.differentiation.half_length;
  const int Mc = filters.comparison.half_length;
  const Eigen::VectorXd& taps = comparison->coefficients(FilterOrder::lowpass);

  FilteredRegressor result;
  result.filters = filters;
  result.lowpass_energy = taps.squaredNorm();
  result.decimation = std::max(1, static_cast<int>(std::floor(std::numbers::pi / (2.0 * filters.comparison.band))));
  const int D = result.decimation;
  const int second = comparison->output_length(pass.samples);  // compared instants
  const int R = (second - 1) / D + 1;
  result.instants = R;
  result.t.resize(R);
  // Instant r is data sample M + M_c + r·D: the centre of L's window r·D .. r·D + 2M_c over the first pass.
  for (int r = 0; r < R; ++r) result.t[r] = data.t[M + Mc + r * D];
  if (data.has_torque()) {
    const Eigen::MatrixXd tau = lowpass_at(data, *comparison, M + Mc, D, R);
    result.tau.resize(static_cast<Eigen::Index>(R) * n);
    for (int r = 0; r < R; ++r) result.tau.segment(static_cast<Eigen::Index>(r) * n, n) = tau.row(r).transpose();
  }

  // Row-major W and a row-major copy of each Y, so that adding one joint's row of Y is a contiguous,
  // vectorised update.
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  RowMajor W = RowMajor::Zero(static_cast<Eigen::Index>(R) * n, p);
  Data workspace(model);
  Eigen::MatrixXd Y(n, p);
  RowMajor Y_rows(n, p);
  std::vector<int> friction_columns;
  for (int begin : {layout.viscous_begin(n), layout.coulomb_begin(n), layout.offset_begin(n), layout.armature_begin(n)}) {
    if (begin >= 0) friction_columns.push_back(begin);
  }
  const int last_sample = std::min(pass.samples - 1, (R - 1) * D + 2 * Mc);
  for (int s = 0; s <= last_sample; ++s) {
    if (cancel && (s & 1023) == 0 && cancel->load(std::memory_order_relaxed)) return FilteredRegressor{};
    regressor(model, workspace, layout, pass.q.col(s), pass.qd.col(s), pass.qdd.col(s), Y);
    Y_rows = Y;
    // Outputs r whose window [r·D, r·D + 2M_c] covers s; tap index s − r·D.
    const int first = std::max(0, (s - 2 * Mc + D - 1) / D);
    const int last = std::min(R - 1, s / D);
    for (int r = first; r <= last; ++r) {
      const double weight = taps[s - r * D];
      for (int k = 0; k < n; ++k) {
        // Row k of Y is zero left of body k's block (a body never loads the joints beyond it), and
        // its friction entries sit on the diagonal of each block.
        const int from = kInertialParametersPerBody * k;
        const int width = kInertialParametersPerBody * (n - k);
        auto row = W.row(static_cast<Eigen::Index>(r) * n + k);
        row.segment(from, width) += weight * Y_rows.row(k).segment(from, width);
        for (int begin : friction_columns) row[begin + k] += weight * Y_rows(k, begin + k);
      }
    }
  }
  result.W = W;
  return result;
}

TorquePrediction predict_torque(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi,
                                const Trajectory& data, const FilterPair& filters) {
  filters.differentiation.validate();
  filters.comparison.validate();
  if (!data.has_torque()) throw InputError("tau", "the data has no tau columns to compare the prediction with");
  const int n = model.joint_count();
  if (pi.size() != layout.size(n)) {
    throw InputError("parameters", "the parameter vector has " + std::to_string(pi.size()) + " entries, the robot " +
                                       std::to_string(layout.size(n)));
  }
  const auto differentiation = cached_filter(filters.differentiation);
  const auto comparison = cached_filter(filters.comparison);
  const FirstPass pass = first_pass(model, data, filters, *differentiation);
  const int M = filters.differentiation.half_length;
  const int Mc = filters.comparison.half_length;

  Eigen::MatrixXd modelled(pass.samples, n);
  Data workspace(model);
  Eigen::VectorXd tau(n);
  for (int s = 0; s < pass.samples; ++s) {
    inverse_dynamics(model, workspace, layout, pi, pass.q.col(s), pass.qd.col(s), pass.qdd.col(s), tau);
    modelled.row(s) = tau.transpose();
  }
  TorquePrediction prediction;
  const int second = comparison->output_length(pass.samples);
  prediction.t = data.t.segment(M + Mc, second);
  prediction.model.resize(second, n);
  Eigen::MatrixXd measured(comparison->output_length(data.samples()), n);  // sample M_c + j of the data
  for (int k = 0; k < n; ++k) comparison->apply(FilterOrder::lowpass, data.tau.col(k), measured.col(k));
  prediction.measured = measured.middleRows(M, second);
  for (int k = 0; k < n; ++k) comparison->apply(FilterOrder::lowpass, modelled.col(k), prediction.model.col(k));
  const Eigen::MatrixXd error = prediction.model - prediction.measured;
  prediction.rms_error = (error.colwise().squaredNorm() / static_cast<double>(second)).cwiseSqrt().transpose();
  prediction.relative_error.resize(n);
  for (int k = 0; k < n; ++k) {
    const double norm = prediction.measured.col(k).norm();
    prediction.relative_error[k] = norm > 0 ? error.col(k).norm() / norm : std::numeric_limits<double>::quiet_NaN();
  }
  const double total = prediction.measured.norm();
  prediction.overall_relative_error = total > 0 ? error.norm() / total : std::numeric_limits<double>::quiet_NaN();
  return prediction;
}

}  // namespace manipid::robot

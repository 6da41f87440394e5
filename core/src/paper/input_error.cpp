// input_error.cpp — filtering for, and the Gram form of, the input-error cost (input_error.h).
#include "manipid/core/paper/input_error.h"

#include "manipid/core/paper/dynamics.h"

#include "vector_clones.h"

#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <limits>

#include <string>
#include <vector>

namespace manipid {
namespace {

using detail::dot;

// One block of the QR below: [R z; B b] (R p × p upper triangular, B m × p new rows) made upper
// triangular again by p Householder reflections, each touching row k of the triangle and the
// rows below it that can be non-zero in column k only: the triangle's rows under the diagonal
// are zero, and of B the first extent[k] rows (the rows are grouped by joint and joint j's
// torque does not involve the masses before j, see the constructor). Rows a reflection does not
// touch stay as they were, so every column keeps that shape. The same reflections as Eigen's
// HouseholderQR of the stacked matrix (beta = −sign(α)·‖column‖, v = [1; x/(α − beta)],
// tau = (beta − α)/beta), in a loop over raw columns, compiled for SSE2 and AVX2: Eigen's
// unblocked kernel for matrices this narrow cost ~1,500 instructions a row here. `work` is
// column-major with leading dimension `ld`: rows 0..p−1 [R z], rows p..p+m−1 [B b]; B is
// overwritten. Returns |b|² after the reflections, what of the torque no β reaches in this block.
MANIPID_VECTOR_CLONES double triangularise_block(double* work, Eigen::Index ld, int p, Eigen::Index m,
                                                 const Eigen::Index* extent) {
  for (int k = 0; k < p; ++k) {
    double* x = work + k * ld + p;
    const Eigen::Index rows = extent[k];
    const double sigma = dot(x, x, rows);
    const double alpha = work[k * ld + k];
    if (sigma <= std::numeric_limits<double>::min()) continue;  // already triangular (Eigen: tau = 0)
    const double norm = std::sqrt(alpha * alpha + sigma);
    const double beta = alpha >= 0.0 ? -norm : norm;
    const double scale = 1.0 / (alpha - beta);
    for (Eigen::Index i = 0; i < rows; ++i) x[i] *= scale;
    const double tau = (beta - alpha) / beta;
    work[k * ld + k] = beta;
    for (int j = k + 1; j <= p; ++j) {  // j = p: the torque column z, b
      double* y = work + j * ld + p;
      const double w = tau * (work[j * ld + k] + dot(x, y, rows));
      work[j * ld + k] -= w;
      for (Eigen::Index i = 0; i < rows; ++i) y[i] -= w * x[i];
    }
  }
  const double* b = work + p * ld + p;
  return dot(b, b, m);
}

}  // namespace

FilteredData filter_for_input_error(const Trajectory& data, const FilterSettings& filter, bool use_reference,
                                    const std::optional<PdController>& controller) {
  filter.validate();
  const int n = data.joint_count();
  const auto differential = cached_filter(filter);
  const int outputs = differential->checked_output_length(data.samples());
  FilteredData result;
  result.filter = filter;
  result.q.resize(outputs, n);
  result.qd.resize(outputs, n);
  result.qdd.resize(outputs, n);
  result.tau.resize(outputs, n);
  for (int j = 0; j < n; ++j) {
    differential->apply_all(data.q.col(j), result.q.col(j), result.qd.col(j), result.qdd.col(j));
  }
  if (use_reference) {
    if (!data.has_reference()) throw InputError("ref", "the data has no ref columns to form the torque from");
    if (!controller) throw InputError("kp", "forming the torque from the reference needs the PD gains kp and kd");
    if (controller->kp.size() != n || controller->kd.size() != n) {
      throw InputError("kp", "kp and kd need " + std::to_string(n) + " entries, one per joint");
    }
    Eigen::VectorXd reference_filtered(outputs);
    for (int j = 0; j < n; ++j) {
      differential->apply(FilterOrder::lowpass, data.ref.col(j), reference_filtered);
      // The controller is linear, so filtering its output equals this combination of filtered inputs.
      result.tau.col(j) = controller->kp[j] * (reference_filtered - result.q.col(j)) - controller->kd[j] * result.qd.col(j);
    }
  } else {
    if (!data.has_torque()) throw InputError("tau", "the data has no tau columns (give ref columns and the PD gains instead)");
    for (int j = 0; j < n; ++j) differential->apply(FilterOrder::lowpass, data.tau.col(j), result.tau.col(j));
  }
  return result;
}

TorqueFit torque_fit(const RobotModel& model, const Parameters& parameters, const Trajectory& data,
                     const FilteredData& filtered) {
  check_parameters(model, parameters);
  const int outputs = filtered.samples();
  const int first = filtered.filter.half_length;
  if (filtered.q.cols() != model.joint_count() || first + outputs > data.samples()) {
    throw InputError("samples", "the filtered data does not belong to this trajectory and model");
  }
  TorqueFit fit;
  fit.t = data.t.segment(first, outputs);
  fit.measured = filtered.tau;
  fit.model.resize(outputs, model.joint_count());
  DynamicsWorkspace workspace(model);
  Eigen::VectorXd tau(model.joint_count());
  for (int i = 0; i < outputs; ++i) {
    inverse_dynamics(model, parameters, workspace, filtered.q.row(i).transpose(), filtered.qd.row(i).transpose(),
                     filtered.qdd.row(i).transpose(), tau);
    fit.model.row(i) = tau.transpose();
  }
  return fit;
}

InputErrorCost::InputErrorCost(const RobotModel& model, FilteredData filtered, Eigen::VectorXd joint_weights)
    : model_(model), data_(std::move(filtered)), weights_(std::move(joint_weights)), products_(parameter_products(model)) {
  const FilteredData& data = data_;
  const int n = model.joint_count();
  const int samples = data.samples();
  if (data.q.cols() != n) throw InputError("q", "the data has " + std::to_string(data.q.cols()) + " joints, the model " + std::to_string(n));
  if (weights_.size() == 0) weights_ = Eigen::VectorXd::Ones(n);
  if (weights_.size() != n || (weights_.array() < 0).any() || !weights_.allFinite()) {
    throw InputError("weights", "joint weights need " + std::to_string(n) + " finite, non-negative entries");
  }
  const int p = products_.size();
  // QR of the stacked weighted regressor (N'·n rows, p columns), a block of rows at a time: each
  // block is factored below the triangle [R | z] so far, which stays in cache where one
  // factorisation of the whole tall matrix streams it from memory p times. Orthogonal steps
  // throughout, so R and z are those of the one-shot QR up to rounding (and row signs, which
  // leave |R β − z|² unchanged); what each block's reflectors leave of τ below R is J⊥'s share.
  // A block's rows are grouped by joint (all its samples' joint-1 rows, then joint 2's, …): the
  // torque of joint j involves the masses j, j+1, … only (the links it carries), so a column of
  // mass c is zero below the rows of joints 1..c, and its reflection touches those rows alone
  // (on the paper's arm a third of the work).
  constexpr int kBlockRows = 512;
  const int block_samples = std::max(1, kBlockRows / n);
  const double root_samples = std::sqrt(static_cast<double>(samples));
  Eigen::MatrixXd work = Eigen::MatrixXd::Zero(p + static_cast<Eigen::Index>(block_samples) * n, p + 1);
  DynamicsWorkspace workspace(model);
  Eigen::MatrixXd Y(static_cast<Eigen::Index>(block_samples) * n, p);  // a block's regressor, sample by sample
  const Eigen::ArrayXd root_weights = weights_.array().sqrt() / root_samples;
  // Joints whose rows column c can reach: its mass's index + 1, as a running maximum so that a
  // reflection never reaches below a later column's extent, whatever order the products come in.
  std::vector<Eigen::Index> joints_reached(static_cast<std::size_t>(p)), extent(static_cast<std::size_t>(p));
  Eigen::Index reach = 0;
  for (int c = 0; c < p; ++c) {
    reach = std::max(reach, static_cast<Eigen::Index>(products_.terms[static_cast<std::size_t>(c)].mass + 1));
    joints_reached[static_cast<std::size_t>(c)] = reach;
  }
  for (int first = 0; first < samples; first += block_samples) {
    const int count = std::min(block_samples, samples - first);
    auto block = Y.topRows(static_cast<Eigen::Index>(count) * n);
    regressor_rows(model, products_, workspace, data.q.middleRows(first, count), data.qd.middleRows(first, count),
                   data.qdd.middleRows(first, count), block);
    // Column by column, so that the writes are contiguous (a row of `work` spans p cache lines).
    for (int j = 0; j < n; ++j) {
      const Eigen::Index top = p + static_cast<Eigen::Index>(j) * count;
      for (int c = 0; c < p; ++c) {
        work.col(c).segment(top, count) = root_weights[j] * block.col(c)(Eigen::seqN(j, count, n));
      }
      work.col(p).segment(top, count) = root_weights[j] * data.tau.col(j).segment(first, count);
    }
    for (int c = 0; c < p; ++c) extent[static_cast<std::size_t>(c)] = joints_reached[static_cast<std::size_t>(c)] * count;
    orthogonal_ += triangularise_block(work.data(), work.rows(), p, static_cast<Eigen::Index>(count) * n, extent.data());
  }
  triangle_ = work.topLeftCorner(p, p);
  rotated_ = work.col(p).head(p);
  // Products the data never excite leave R singular; the rank-revealing solve finds what
  // part of z no β reaches.
  const Eigen::VectorXd best = triangle_.completeOrthogonalDecomposition().solve(rotated_);
  floor_ = orthogonal_ + (triangle_ * best - rotated_).squaredNorm();
}

Eigen::VectorXd InputErrorCost::residual(const Parameters& parameters, Eigen::MatrixXd* jacobian) const {
  if (jacobian) *jacobian = triangle_.triangularView<Eigen::Upper>() * products_.jacobian(parameters);
  return triangle_.triangularView<Eigen::Upper>() * products_.evaluate(parameters) - rotated_;
}

double InputErrorCost::evaluate(const Parameters& parameters, Eigen::VectorXd* gradient) const {
  const Eigen::VectorXd r = residual(parameters);
  if (gradient) {
    *gradient = 2.0 * products_.jacobian(parameters).transpose() * (triangle_.triangularView<Eigen::Upper>().transpose() * r);
  }
  return r.squaredNorm() + orthogonal_;
}

double InputErrorCost::evaluate_direct(const Parameters& parameters) const {
  const int n = model_.joint_count();
  DynamicsWorkspace workspace(model_);
  Eigen::VectorXd tau(n), q(n), qd(n), qdd(n);
  double sum = 0.0;
  for (int t = 0; t < data_.samples(); ++t) {
    q = data_.q.row(t).transpose();
    qd = data_.qd.row(t).transpose();
    qdd = data_.qdd.row(t).transpose();
    inverse_dynamics(model_, parameters, workspace, q, qd, qdd, tau);
    sum += (weights_.array() * (tau - data_.tau.row(t).transpose()).array().square()).sum();
  }
  return sum / data_.samples();
}

Eigen::MatrixXd InputErrorCost::gauss_newton_matrix(const Parameters& parameters) const {
  const Eigen::MatrixXd RG = triangle_.triangularView<Eigen::Upper>() * products_.jacobian(parameters);
  return static_cast<double>(data_.samples()) * RG.transpose() * RG;
}

}  // namespace manipid

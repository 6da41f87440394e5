// excitation_criterion.cpp — the excitation's criterion: the base regressor Y_b stacked over one period, its
// column-scaled condition number and the log det of its information matrix (robot/excitation.h's file comment).
#include "robot/excitation_internal.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/payload.h"
#include "manipid/core/robot/regressor.h"
#include "numbers.h"

#include <Eigen/QR>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <string>

namespace manipid::robot {
namespace detail {
namespace {

using manipid::detail::kInfinity;

/// The optimiser's criterion goes through the Gram matrix, which squares the condition number: eigenvalue
/// ratios below ε ≈ 2.2e-16 are rounding, so a cond beyond ~1e8 only means "very bad" there (the reported
/// figure comes from an SVD). Eigenvalues are floored at λ_max / kConditionCap² so that the log stays
/// finite when rounding makes one zero or negative.
constexpr double kConditionCap = 1e16;
/// log det for a trajectory that leaves some base parameter unseen: below any real one (those are O(100)).
constexpr double kUnseenLogDet = -1e6;

}  // namespace

CriterionColumns criterion_columns(const Model& model, const ExcitationOptions& options) {
  CriterionColumns columns;
  if (options.target == ExcitationTarget::payload) {
    const int first = kInertialParametersPerBody * (model.joint_count() - 1);
    for (int i = 0; i < kInertialParametersPerBody; ++i) columns.selected.push_back(first + i);
    columns.transform = payload_to_last_body(model);
    return columns;
  }
  BaseParameterOptions base_options;
  base_options.cancel = options.cancel;
  columns.selected = base_parameters(model, options.layout, base_options).independent;
  if (columns.selected.empty()) throw InputError("model", "the model's torques determine no parameter to identify");
  return columns;
}

CriterionWorkspace::CriterionWorkspace(const Model& model, const ParameterLayout& layout,
                                       const CriterionColumns& columns, double period, int harmonics, int samples,
                                       const std::atomic<bool>* cancel)
    : model_(model),
      layout_(layout),
      columns_(columns),
      n_(model.joint_count()),
      samples_(samples),
      table_(period, harmonics, samples, Instants::midpoints),
      data_(model),
      q_(n_, samples),
      qd_(n_, samples),
      qdd_(n_, samples),
      Y_(static_cast<Eigen::Index>(samples) * n_, layout.size(n_)),
      selected_(columns.transform.size() ? static_cast<Eigen::Index>(samples) * n_ : 0,
                columns.transform.size() ? static_cast<Eigen::Index>(columns.selected.size()) : 0),
      Yb_(static_cast<Eigen::Index>(samples) * n_, columns.size()),
      gram_(columns.size(), columns.size()),
      scaled_gram_(columns.size(), columns.size()),
      norms_(columns.size()),
      eigen_(columns.size()),
      cancel_(cancel) {}

Eigen::Index CriterionWorkspace::rows_between_checkpoints(Eigen::Index columns) const {
  const double work = static_cast<double>(Yb_.rows()) * static_cast<double>(columns) * static_cast<double>(columns);
  if (work <= kCheckpointWork) return Yb_.rows();
  return std::max<Eigen::Index>(columns, static_cast<Eigen::Index>(kCheckpointWork / (static_cast<double>(columns) * static_cast<double>(columns))));
}

void CriterionWorkspace::stack(const Eigen::VectorXd& q0, const Eigen::MatrixXd& K) {
  q_.noalias() = K * table_.position;
  q_.colwise() += q0;
  qd_.noalias() = K * table_.velocity;
  qdd_.noalias() = K * table_.acceleration;
  stacked_regressor(model_, data_, layout_, q_, qd_, qdd_, Y_);
  Eigen::MatrixXd& selected = columns_.transform.size() ? selected_ : Yb_;
  for (std::size_t i = 0; i < columns_.selected.size(); ++i) {
    selected.col(static_cast<Eigen::Index>(i)) = Y_.col(columns_.selected[i]);
  }
  if (columns_.transform.size()) Yb_.noalias() = selected_ * columns_.transform;
}

void CriterionWorkspace::fast_criteria(double& log_condition, double& log_det) {
  gram_.setZero();
  const Eigen::Index b = gram_.rows();
  const Eigen::Index block = rows_between_checkpoints(b);
  for (Eigen::Index row = 0; row < Yb_.rows(); row += block) {
    if (row > 0) checkpoint(cancel_, "the excitation's criterion");
    const Eigen::Index count = std::min(block, Yb_.rows() - row);
    gram_.selfadjointView<Eigen::Lower>().rankUpdate(Yb_.middleRows(row, count).transpose());
  }
  for (Eigen::Index i = 0; i < b; ++i) norms_[i] = std::sqrt(gram_(i, i));
  // A base column that is zero over the whole trajectory (a joint frozen at its limit: a parameter it
  // cannot see), or anything not finite: the worst value, never a NaN into the eigensolver.
  if (b == 0 || !gram_.allFinite() || !(norms_.minCoeff() > 0.0)) {
    log_condition = std::log(kConditionCap);
    log_det = kUnseenLogDet;
    return;
  }
  for (Eigen::Index j = 0; j < b; ++j) {
    for (Eigen::Index i = j; i < b; ++i) scaled_gram_(i, j) = gram_(i, j) / (norms_[i] * norms_[j]);
  }
  eigen_.compute(scaled_gram_, Eigen::EigenvaluesOnly);
  const Eigen::VectorXd& lambda = eigen_.eigenvalues();  // ascending
  const double top = lambda[b - 1];
  const double floor = top / (kConditionCap * kConditionCap);
  const double bottom = std::max(lambda[0], floor);
  log_condition = 0.5 * std::log(top / bottom);
  double sum = 0.0;
  for (Eigen::Index i = 0; i < b; ++i) sum += std::log(std::max(lambda[i], floor)) + 2.0 * std::log(norms_[i]);
  log_det = sum - static_cast<double>(b) * std::log(static_cast<double>(samples_));
}

ExcitationQuality CriterionWorkspace::exact_quality() const {
  ExcitationQuality quality;
  quality.base_parameters = columns_.size();
  quality.samples = samples_;
  const Eigen::Index b = Yb_.cols();
  if (b == 0) {
    quality.condition_number = kInfinity;
    quality.log_det = -kInfinity;
    return quality;
  }
  Eigen::VectorXd norms = Yb_.colwise().norm().transpose();
  if (!Yb_.allFinite() || !(norms.minCoeff() > 0.0)) {
    quality.condition_number = kInfinity;
    quality.log_det = -kInfinity;
    return quality;
  }
  Eigen::VectorXd sigma;  // descending
  const Eigen::Index block = rows_between_checkpoints(b);
  if (block >= Yb_.rows()) {
    const Eigen::MatrixXd scaled = Yb_ * norms.cwiseInverse().asDiagonal();
    sigma = Eigen::BDCSVD<Eigen::MatrixXd>(scaled).singularValues();
  } else {
    // In row blocks: the R of a QR has the singular values of the matrix, and the R of [R; next rows] is
    // that of every row so far. Each block of at least 4b rows, so the b×b R is a small part of the work.
    const Eigen::Index rows = std::max(block, 4 * b);
    Eigen::MatrixXd stacked(b + rows, b);
    Eigen::MatrixXd R = Eigen::MatrixXd::Zero(b, b);
    for (Eigen::Index row = 0; row < Yb_.rows(); row += rows) {
      checkpoint(cancel_, "the excitation's condition number");
      const Eigen::Index count = std::min(rows, Yb_.rows() - row);
      stacked.topRows(b) = R;
      stacked.middleRows(b, count) = Yb_.middleRows(row, count) * norms.cwiseInverse().asDiagonal();
      Eigen::Ref<Eigen::MatrixXd> rows_so_far(stacked.topRows(b + count));
      const Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(rows_so_far);  // in place
      R = qr.matrixQR().topRows(b).triangularView<Eigen::Upper>();
    }
    checkpoint(cancel_, "the excitation's condition number");
    sigma = Eigen::BDCSVD<Eigen::MatrixXd>(R).singularValues();
  }
  const double smallest = sigma[b - 1];
  quality.condition_number = smallest > 0.0 ? sigma[0] / smallest : kInfinity;
  if (smallest > 0.0) {
    quality.log_det = 2.0 * (sigma.array().log().sum() + norms.array().log().sum()) -
                      static_cast<double>(b) * std::log(static_cast<double>(samples_));
  } else {
    quality.log_det = -kInfinity;
  }
  return quality;
}

}  // namespace detail

const char* to_string(ExcitationCriterion criterion) {
  switch (criterion) {
    case ExcitationCriterion::condition: return "condition";
    case ExcitationCriterion::logdet: return "logdet";
  }
  return "unknown";
}

const char* to_string(ExcitationTarget target) {
  switch (target) {
    case ExcitationTarget::arm: return "arm";
    case ExcitationTarget::payload: return "payload";
  }
  return "unknown";
}

ExcitationTarget parse_excitation_target(const std::string& text, const std::string& field) {
  if (text == "arm") return ExcitationTarget::arm;
  if (text == "payload") return ExcitationTarget::payload;
  throw InputError(field, "unknown target '" + text + "' (known: arm, payload)");
}

ExcitationCriterion parse_excitation_criterion(const std::string& text, const std::string& field) {
  if (text == "condition") return ExcitationCriterion::condition;
  if (text == "logdet") return ExcitationCriterion::logdet;
  throw InputError(field, "unknown criterion '" + text + "' (known: condition, logdet)");
}

ExcitationQuality excitation_quality(const Model& model, const FourierTrajectory& trajectory,
                                     const ExcitationOptions& options) {
  trajectory.validate();
  if (trajectory.joint_count() != model.joint_count()) {
    throw InputError("q0", "the trajectory has " + std::to_string(trajectory.joint_count()) + " joints, the model " +
                               std::to_string(model.joint_count()));
  }
  const int L = trajectory.harmonics();
  const int samples = options.samples > 0 ? options.samples : std::max(200, 40 * L);
  if (samples < 8 * L || samples > detail::kMaxSamples) {
    throw InputError("samples", "samples must be 0 (automatic) or lie in " + std::to_string(8 * L) + ".." +
                                    std::to_string(detail::kMaxSamples) + " for " + std::to_string(L) + " harmonics");
  }
  const detail::CriterionColumns columns = detail::criterion_columns(model, options);
  detail::CriterionWorkspace workspace(model, options.layout, columns, trajectory.period, L, samples);
  workspace.stack(trajectory.q0, detail::stacked_coefficients(trajectory));
  return workspace.exact_quality();
}

}  // namespace manipid::robot

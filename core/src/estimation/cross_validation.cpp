// cross_validation.cpp — time bins, folds, and held-out errors of ridge fits from binned sums
// (estimation/cross_validation.h).
#include "manipid/core/estimation/cross_validation.h"

#include "manipid/core/errors.h"
#include "manipid/core/estimation/rules.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>

namespace manipid::estimation {

TimeBins::TimeBins(const std::vector<std::pair<double, double>>& spans, int folds, int bins_per_fold)
    : spans_(spans), folds_(folds), per_fold_(bins_per_fold) {
  if (folds < 2 || bins_per_fold < 1) throw InputError("folds", "cross-validation needs at least 2 folds of 1 bin");
}

std::vector<std::pair<double, double>> run_spans(const std::vector<int>& run_of_row, const std::vector<double>& time_of_row,
                                                 int runs) {
  std::vector<std::pair<double, double>> spans(static_cast<std::size_t>(runs), {std::numeric_limits<double>::infinity(),
                                                                               -std::numeric_limits<double>::infinity()});
  for (std::size_t r = 0; r < run_of_row.size(); ++r) {
    auto& [from, to] = spans[static_cast<std::size_t>(run_of_row[r])];
    from = std::min(from, time_of_row[r]);
    to = std::max(to, time_of_row[r]);
  }
  return spans;
}

std::vector<int> bins_of_rows(const TimeBins& bins, const std::vector<int>& run_of_row, const std::vector<double>& time_of_row) {
  std::vector<int> of_row(run_of_row.size());
  for (std::size_t r = 0; r < of_row.size(); ++r) of_row[r] = bins.bin(run_of_row[r], time_of_row[r]);
  return of_row;
}

int TimeBins::bin(int run, double t) const {
  const auto& [from, to] = spans_[static_cast<std::size_t>(run)];
  if (!(t >= from && t <= to) || !(to > from)) return -1;
  const int per_run = folds_ * per_fold_;
  const int index = std::min(per_run - 1, static_cast<int>((t - from) / (to - from) * per_run));
  return run * per_run + index;
}

std::vector<int> TimeBins::test_bins(int fold) const {
  std::vector<int> bins;
  const int per_run = folds_ * per_fold_;
  for (int run = 0; run < static_cast<int>(spans_.size()); ++run) {
    for (int b = 0; b < per_fold_; ++b) bins.push_back(run * per_run + fold * per_fold_ + b);
  }
  return bins;
}

std::vector<int> TimeBins::train_bins(int fold, double guard) const {
  std::vector<int> bins;
  const int per_run = folds_ * per_fold_;
  for (int run = 0; run < static_cast<int>(spans_.size()); ++run) {
    const auto& [from, to] = spans_[static_cast<std::size_t>(run)];
    const double width = (to - from) / per_run;
    const double test_from = from + width * fold * per_fold_, test_to = test_from + width * per_fold_;
    for (int b = 0; b < per_run; ++b) {
      const double bin_from = from + width * b, bin_to = bin_from + width;
      if (bin_to <= test_from - guard || bin_from >= test_to + guard) bins.push_back(run * per_run + b);
    }
  }
  return bins;
}

void BinnedSums::total(const std::vector<int>& bins, Eigen::MatrixXd& G, Eigen::VectorXd& h, double& c) const {
  const Eigen::Index p = gram.empty() ? 0 : gram.front().rows();
  G = Eigen::MatrixXd::Zero(p, p);
  h = Eigen::VectorXd::Zero(p);
  c = 0.0;
  for (int b : bins) {
    G += gram[static_cast<std::size_t>(b)];
    h += moment[static_cast<std::size_t>(b)];
    c += energy[static_cast<std::size_t>(b)];
  }
}

BinnedSums bin_rows(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::VectorXd>& y,
                    const std::vector<int>& bin_of_row, int bins) {
  const Eigen::Index p = A.cols();
  BinnedSums sums;
  sums.gram.assign(static_cast<std::size_t>(bins), Eigen::MatrixXd::Zero(p, p));
  sums.moment.assign(static_cast<std::size_t>(bins), Eigen::VectorXd::Zero(p));
  sums.energy.assign(static_cast<std::size_t>(bins), 0.0);
  // Rows of a bin are contiguous in time order here, but not required to be: gather each bin's rows, then one
  // matrix product per bin.
  std::vector<std::vector<Eigen::Index>> rows(static_cast<std::size_t>(bins));
  for (Eigen::Index r = 0; r < A.rows(); ++r) {
    const int b = bin_of_row[static_cast<std::size_t>(r)];
    if (b >= 0) rows[static_cast<std::size_t>(b)].push_back(r);
  }
  for (int b = 0; b < bins; ++b) {
    const auto& list = rows[static_cast<std::size_t>(b)];
    if (list.empty()) continue;
    Eigen::MatrixXd block(static_cast<Eigen::Index>(list.size()), p);
    Eigen::VectorXd target(static_cast<Eigen::Index>(list.size()));
    for (std::size_t i = 0; i < list.size(); ++i) {
      block.row(static_cast<Eigen::Index>(i)) = A.row(list[i]);
      target[static_cast<Eigen::Index>(i)] = y[list[i]];
    }
    auto& G = sums.gram[static_cast<std::size_t>(b)];
    G.selfadjointView<Eigen::Lower>().rankUpdate(block.transpose());
    G = G.selfadjointView<Eigen::Lower>();
    sums.moment[static_cast<std::size_t>(b)] = block.transpose() * target;
    sums.energy[static_cast<std::size_t>(b)] = target.squaredNorm();
  }
  return sums;
}

double CrossValidation::relative_error(int i) const {
  return target_energy > 0 ? std::sqrt(std::max(0.0, squared_error[i]) / target_energy) : std::numeric_limits<double>::quiet_NaN();
}

std::vector<double> default_ridges() {
  std::vector<double> ridges{0.0};
  for (int e = -12; e <= 0; ++e) ridges.push_back(std::pow(10.0, e / 2.0));
  return ridges;
}

CrossValidation cross_validate(const BinnedSums& training, const BinnedSums& target, const TimeBins& bins, double guard,
                               const std::vector<int>& columns, const Eigen::VectorXd& prior,
                               const std::vector<double>& ridges) {
  CrossValidation result;
  result.ridges = ridges;
  result.squared_error = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(ridges.size()));
  const Eigen::Index m = static_cast<Eigen::Index>(columns.size());
  // Column scales from all training rows, as the final solve scales them.
  Eigen::MatrixXd G_all;
  Eigen::VectorXd h_all;
  double c_all = 0.0;
  std::vector<int> every(static_cast<std::size_t>(bins.count()));
  for (int b = 0; b < bins.count(); ++b) every[static_cast<std::size_t>(b)] = b;
  training.total(every, G_all, h_all, c_all);
  Eigen::VectorXd scale(m);
  double largest = 0.0;
  for (Eigen::Index j = 0; j < m; ++j) {
    const int c = columns[static_cast<std::size_t>(j)];
    scale[j] = std::sqrt(std::max(0.0, G_all(c, c)));
    largest = std::max(largest, scale[j]);
  }
  std::vector<Eigen::Index> kept;
  for (Eigen::Index j = 0; j < m; ++j) {
    if (scale[j] > kNegligibleColumn * largest) kept.push_back(j);
  }
  const Eigen::Index k = static_cast<Eigen::Index>(kept.size());

  for (int fold = 0; fold < bins.folds(); ++fold) {
    Eigen::MatrixXd G, Gt;
    Eigen::VectorXd h, ht;
    double c = 0.0, ct = 0.0;
    training.total(bins.train_bins(fold, guard), G, h, c);
    target.total(bins.test_bins(fold), Gt, ht, ct);
    result.target_energy += ct;
    // The training sums in scaled coordinates over the kept columns, the rest (and every column outside
    // `columns`) at the prior: h − G β₀ is what the kept columns must explain.
    const Eigen::VectorXd h_rest = h - G * prior;
    Eigen::MatrixXd Gs(k, k);
    Eigen::VectorXd hs(k);
    for (Eigen::Index a = 0; a < k; ++a) {
      const Eigen::Index ca = columns[static_cast<std::size_t>(kept[static_cast<std::size_t>(a)])];
      const double sa = scale[kept[static_cast<std::size_t>(a)]];
      hs[a] = h_rest[ca] / sa;
      for (Eigen::Index b = 0; b < k; ++b) {
        const Eigen::Index cb = columns[static_cast<std::size_t>(kept[static_cast<std::size_t>(b)])];
        Gs(a, b) = G(ca, cb) / (sa * scale[kept[static_cast<std::size_t>(b)]]);
      }
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(Gs);
    const Eigen::VectorXd values = eigen.eigenvalues().cwiseMax(0.0);  // ascending
    const Eigen::MatrixXd& V = eigen.eigenvectors();
    const double top = values.size() ? values[values.size() - 1] : 0.0;
    const Eigen::VectorXd projected = V.transpose() * hs;
    for (std::size_t r = 0; r < ridges.size(); ++r) {
      const double ridge2 = ridges[r] * ridges[r] * top;
      Eigen::VectorXd dx = Eigen::VectorXd::Zero(k);
      for (Eigen::Index e = 0; e < values.size(); ++e) {
        if (!(values[e] > kUnidentifiableRatio * kUnidentifiableRatio * top)) continue;
        dx += V.col(e) * (projected[e] / (values[e] + ridge2));
      }
      Eigen::VectorXd beta = prior;
      for (Eigen::Index a = 0; a < k; ++a) {
        beta[columns[static_cast<std::size_t>(kept[static_cast<std::size_t>(a)])]] += dx[a] / scale[kept[static_cast<std::size_t>(a)]];
      }
      result.squared_error[static_cast<Eigen::Index>(r)] += beta.dot(Gt * beta) - 2.0 * beta.dot(ht) + ct;
    }
  }
  for (Eigen::Index r = 0; r < result.squared_error.size(); ++r) {
    if (result.squared_error[r] <= result.squared_error[result.best] * (1.0 + 1e-12)) result.best = static_cast<int>(r);
  }
  return result;
}

}  // namespace manipid::estimation

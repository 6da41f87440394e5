// cross_validation.h — blocked cross-validation over time for linear least squares: which candidate rows
// (a filter, a friction model) and which ridge toward the prior predict held-out motion best, every
// candidate judged against one common target, so that no candidate can win by changing what it is judged on.
//
// Each run is cut into `folds` equal segments of `bins_per_fold` time bins. Fold k holds out segment k of
// every run: it fits on the bins farther than `guard` seconds from that segment (rows are low-passed, so
// neighbours share information) and measures the squared error of the fit's prediction on the target's rows
// in the segment. Rows enter through their sums per bin (Gram AᵀA, Aᵀy, yᵀy), so a fold costs one
// eigen-decomposition of dim β, whatever the number of rows; the solve is linear_least_squares.h's rule on
// the normal equations (columns scaled to unit norm, negligible columns and undetermined directions at the
// prior, shrinkage f = s²/(s² + ρ² s_1²)).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace manipid::estimation {

/// The time bins of a set of runs and the folds over them.
class TimeBins {
 public:
  /// `spans`: each run's first and last row time, s. Throws InputError("folds") for folds < 2 or
  /// bins_per_fold < 1.
  TimeBins(const std::vector<std::pair<double, double>>& spans, int folds, int bins_per_fold);
  int count() const { return static_cast<int>(spans_.size()) * folds_ * per_fold_; }
  int folds() const { return folds_; }
  /// The bin of time t in run `run`; −1 outside the run's span.
  int bin(int run, double t) const;
  /// Fold k: the bins it tests on, and those it trains on (farther than `guard` s from the tested segment).
  std::vector<int> test_bins(int fold) const;
  std::vector<int> train_bins(int fold, double guard) const;

 private:
  std::vector<std::pair<double, double>> spans_;
  int folds_, per_fold_;
};

/// Each of `runs` runs' first and last row time (TimeBins' spans), from where each row lies: row r is of run
/// run_of_row[r] at time time_of_row[r], s.
std::vector<std::pair<double, double>> run_spans(const std::vector<int>& run_of_row, const std::vector<double>& time_of_row,
                                                 int runs);
/// Each row's bin (−1 outside every run's span): what bin_rows() takes.
std::vector<int> bins_of_rows(const TimeBins& bins, const std::vector<int>& run_of_row, const std::vector<double>& time_of_row);

/// The sums of one set of rows by bin.
struct BinnedSums {
  std::vector<Eigen::MatrixXd> gram;    ///< AᵀA per bin
  std::vector<Eigen::VectorXd> moment;  ///< Aᵀy per bin
  std::vector<double> energy;           ///< yᵀy per bin
  /// The sums over `bins`.
  void total(const std::vector<int>& bins, Eigen::MatrixXd& G, Eigen::VectorXd& h, double& c) const;
};
/// Rows r with bin_of_row[r] ≥ 0 added to their bin (`bins` bins).
BinnedSums bin_rows(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::VectorXd>& y,
                    const std::vector<int>& bin_of_row, int bins);

/// What cross_validate() found for each ridge.
struct CrossValidation {
  std::vector<double> ridges;
  Eigen::VectorXd squared_error;  ///< per ridge: the held-out squared error summed over the folds
  double target_energy = 0.0;     ///< the held-out target's squared norm summed over the folds
  int best = 0;                   ///< the ridge with the smallest error (the largest on ties)
  /// √(error / target energy) of ridge i: the held-out relative RMS error.
  double relative_error(int i) const;
  double best_relative_error() const { return relative_error(best); }
};

/// For each fold and ridge: β fitted on the fold's training bins of `training`, over `columns` of β (the
/// others at `prior`), scored on the fold's test bins of `target` (the same parameters). `prior`: dim β.
CrossValidation cross_validate(const BinnedSums& training, const BinnedSums& target, const TimeBins& bins, double guard,
                               const std::vector<int>& columns, const Eigen::VectorXd& prior,
                               const std::vector<double>& ridges);

/// The ridge grid cross_validate() is given by default: 0 and 10^-6 .. 1 in steps of √10.
std::vector<double> default_ridges();

}  // namespace manipid::estimation

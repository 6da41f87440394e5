// uncertainty.cpp — standard errors and identifiability (uncertainty.h).
//
// Work in relative coordinates (δθ_i / θ_i) so that kg and m compare: H_s = D H D with
// D = diag(|θ|). Its eigenvectors with (near) zero eigenvalues are parameter combinations
// the data cannot see; the covariance σ² H_s⁺ is the pseudo-inverse restricted to what the
// data do see, so the standard errors of the other parameters stay meaningful.
#include "paper/uncertainty.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

namespace manipid::detail {
namespace {

std::string join(const std::vector<std::string>& words) {
  std::string text;
  for (std::size_t i = 0; i < words.size(); ++i) {
    text += words[i];
    if (i + 2 < words.size()) text += ", ";
    else if (i + 2 == words.size()) text += " and ";
  }
  return text;
}

// Exponents of a product term over all 2n parameters.
Eigen::VectorXd term_exponents(const ParameterProducts::Term& term, int n) {
  Eigen::VectorXd e = Eigen::VectorXd::Zero(2 * n);
  e[term.mass] += 1;
  if (term.first >= 0) e[n + term.first] += 1;
  if (term.second >= 0) e[n + term.second] += 1;
  return e;
}

}  // namespace

Uncertainty assess_uncertainty(const UncertaintyInput& input) {
  const int total = static_cast<int>(input.theta.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<int> free_index;
  for (int i = 0; i < total; ++i) {
    if (input.free[i]) free_index.push_back(i);
  }
  const int p = static_cast<int>(free_index.size());
  Uncertainty result;
  result.std_errors = Eigen::VectorXd::Constant(total, nan);
  result.correlation = Eigen::MatrixXd::Constant(p, p, nan);
  if (p == 0) return result;

  // Nothing non-finite ever reaches an eigensolver (Eigen 3.4's SelfAdjointEigenSolver reads
  // out of bounds on NaN input): say why instead.
  const Eigen::MatrixXd& structure = input.structure.size() ? input.structure : input.information;
  if (!input.theta.allFinite()) {
    result.unavailable = "the estimate is not a finite number";
    return result;
  }
  if (!input.information.allFinite() || !structure.allFinite() || !std::isfinite(input.residual_variance)) {
    result.unavailable = "the model's sensitivities at the estimate are not finite numbers";
    return result;
  }

  Eigen::VectorXd scale(p);
  for (int a = 0; a < p; ++a) scale[a] = input.theta[free_index[a]] != 0.0 ? std::abs(input.theta[free_index[a]]) : 1.0;
  IdentifiabilityReport& report = result.report;

  // Which directions the data cannot see, decided on the exact-structure matrix.
  Eigen::MatrixXd null_basis;
  const Eigen::MatrixXd basis = identifiable_basis(structure, input.theta, input.free, &null_basis);
  std::vector<Eigen::VectorXd> null_directions;
  std::set<int> unidentifiable;  // free positions
  for (int k = 0; k < null_basis.cols(); ++k) {
    const Eigen::VectorXd v = null_basis.col(k);
    null_directions.push_back(v);
    for (int a = 0; a < p; ++a) {
      if (std::abs(v[a]) > 0.05 * v.cwiseAbs().maxCoeff()) unidentifiable.insert(a);
    }
  }

  // The information restricted to the identifiable directions, in relative coordinates.
  Eigen::MatrixXd scaled(p, p);
  for (int a = 0; a < p; ++a)
    for (int b = 0; b < p; ++b) scaled(a, b) = scale[a] * input.information(free_index[a], free_index[b]) * scale[b];
  const Eigen::MatrixXd reduced = basis.transpose() * scaled * basis;
  Eigen::VectorXd values;  // ascending
  Eigen::MatrixXd vectors;
  if (reduced.size() > 0) {  // an empty matrix when the data see no direction at all
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(reduced);
    values = eigen.eigenvalues().cwiseMax(0.0);
    vectors = eigen.eigenvectors();
  }
  const double largest = values.size() ? values.maxCoeff() : 0.0;
  Eigen::VectorXd singular = Eigen::VectorXd::Zero(p);
  singular.head(values.size()) = values.reverse().cwiseSqrt();
  report.singular_values = singular;

  Eigen::MatrixXd inverse = Eigen::MatrixXd::Zero(p, p);
  for (int k = 0; k < values.size(); ++k) {
    const Eigen::VectorXd v = basis * vectors.col(k);
    const double ratio = largest > 0 ? std::sqrt(values[k] / largest) : 0.0;
    if (values[k] <= 0.0) continue;
    inverse += v * v.transpose() / values[k];
    if (ratio < kWeakRatio) {
      // The parameters that carry this direction: its components within a third of the largest.
      std::vector<std::string> involved;
      const double biggest = v.cwiseAbs().maxCoeff();
      for (int a = 0; a < p; ++a) {
        if (std::abs(v[a]) >= biggest / 3.0) involved.push_back(input.names[free_index[a]]);
      }
      std::ostringstream text;
      text << "the data barely separate " << join(involved) << " (relative singular value " << ratio
           << "): their estimates are strongly correlated and their standard errors large";
      report.findings.push_back(text.str());
    }
  }
  Eigen::MatrixXd covariance = input.residual_variance * inverse;  // relative coordinates
  if (input.added_covariance.rows() == total && input.added_covariance.allFinite()) {
    for (int a = 0; a < p; ++a)
      for (int b = 0; b < p; ++b) covariance(a, b) += input.added_covariance(free_index[a], free_index[b]) / (scale[a] * scale[b]);
  }

  for (int a = 0; a < p; ++a) {
    if (unidentifiable.count(a)) continue;
    result.std_errors[free_index[a]] = scale[a] * std::sqrt(covariance(a, a));
    for (int b = 0; b < p; ++b) {
      if (unidentifiable.count(b)) continue;
      result.correlation(a, b) = covariance(a, b) / std::sqrt(covariance(a, a) * covariance(b, b));
    }
  }
  for (int a : unidentifiable) report.unidentifiable.push_back(input.names[free_index[a]]);

  // Name what the data determine instead: a model product over the unidentifiable parameters
  // that every null direction leaves unchanged (in relative coordinates Σ e_i v_i = 0).
  if (!unidentifiable.empty()) {
    const int n = total / 2;
    std::set<int> covered;
    if (input.products) {
      for (const auto& term : input.products->terms) {
        const Eigen::VectorXd e = term_exponents(term, n);
        Eigen::VectorXd e_free(p);
        bool inside = true, touches = false;
        for (int i = 0; i < total; ++i) {
          if (e[i] == 0) continue;
          const auto position = std::find(free_index.begin(), free_index.end(), i) - free_index.begin();
          if (position == p || !unidentifiable.count(static_cast<int>(position))) inside = false;
        }
        for (int a = 0; a < p; ++a) {
          e_free[a] = e[free_index[a]];
          if (e_free[a] != 0 && unidentifiable.count(a)) touches = true;
        }
        if (!inside || !touches) continue;
        bool invariant = true;
        for (const auto& v : null_directions) invariant = invariant && std::abs(e_free.dot(v)) < 1e-4 * e_free.norm();
        // A single parameter is never "a combination".
        if (!invariant || (e_free.array() != 0).count() < 2) continue;
        double value = 1.0;
        for (int i = 0; i < total; ++i) value *= std::pow(input.theta[i], e[i]);
        IdentifiableCombination combination;
        combination.name = input.products->name(static_cast<int>(&term - input.products->terms.data()));
        combination.value = value;
        combination.std_error = std::abs(value) * std::sqrt(std::max(0.0, e_free.dot(covariance * e_free)));
        std::vector<std::string> members;
        for (int a = 0; a < p; ++a) {
          if (e_free[a] != 0) {
            members.push_back(input.names[free_index[a]]);
            covered.insert(a);
          }
        }
        std::ostringstream text;
        text << join(members) << " enter the model only as " << combination.name << ": the data determine "
             << combination.name << " = " << combination.value << " ± " << combination.std_error
             << " (one standard error), not " << join(members)
             << " separately. Fix one of them at a known value to estimate the other.";
        report.findings.push_back(text.str());
        report.combinations.push_back(combination);
      }
    }
    std::vector<std::string> rest;
    for (int a : unidentifiable) {
      if (!covered.count(a)) rest.push_back(input.names[free_index[a]]);
    }
    if (!rest.empty()) {
      report.findings.push_back("the data cannot determine " + join(rest) +
                                ": some combination of them leaves the cost unchanged (no excitation, or a "
                                "structural ambiguity); their estimates are arbitrary");
    }
  }
  return result;
}

Eigen::MatrixXd identifiable_basis(const Eigen::MatrixXd& information, const Eigen::VectorXd& theta,
                                   const std::vector<bool>& free, Eigen::MatrixXd* null_basis) {
  std::vector<int> free_index;
  for (int i = 0; i < theta.size(); ++i) {
    if (free[i]) free_index.push_back(i);
  }
  const int p = static_cast<int>(free_index.size());
  Eigen::MatrixXd scaled(p, p);
  for (int a = 0; a < p; ++a) {
    for (int b = 0; b < p; ++b) {
      const double sa = theta[free_index[a]] != 0.0 ? std::abs(theta[free_index[a]]) : 1.0;
      const double sb = theta[free_index[b]] != 0.0 ? std::abs(theta[free_index[b]]) : 1.0;
      scaled(a, b) = sa * information(free_index[a], free_index[b]) * sb;
    }
  }
  if (p == 0 || !scaled.allFinite()) {
    if (null_basis) *null_basis = Eigen::MatrixXd::Identity(p, p);
    return Eigen::MatrixXd(p, 0);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
  const Eigen::VectorXd values = eigen.eigenvalues().cwiseMax(0.0);
  const double largest = values.maxCoeff();
  int null_count = 0;
  while (null_count < p && (largest <= 0 || std::sqrt(values[null_count] / largest) < kUnidentifiableRatio)) ++null_count;
  if (null_basis) *null_basis = eigen.eigenvectors().leftCols(null_count);
  return eigen.eigenvectors().rightCols(p - null_count);
}

}  // namespace manipid::detail

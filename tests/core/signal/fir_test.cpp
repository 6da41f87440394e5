// fir_test.cpp — the FIR engine's two modes (core/src/signal/fir.h): the full mode against the plain sum, the strided mode against the full one.
#include "signal/fir.h"

#include "manipid/core/errors.h"
#include "manipid/core/signal/filters.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

namespace manipid {
namespace {

using detail::fir::Parity;
using detail::fir::StridedBank;

Eigen::VectorXd random_signal(int samples, unsigned seed) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd x(samples);
  double walk = 0.0;
  for (int i = 0; i < samples; ++i) x[i] = (walk += 0.01 * normal(engine)) + 1e-3 * normal(engine);
  return x;
}

// Σ_n c[n] x[j + n] over the whole (2M + 1)-long filter: the definition, summed plainly.
double plain_sum(const Eigen::VectorXd& c, const Eigen::VectorXd& x, Eigen::Index j) {
  double sum = 0.0;
  for (Eigen::Index n = 0; n < c.size(); ++n) sum += c[n] * x[j + n];
  return sum;
}

// The engine's sums agree to rounding: a few ulps of Σ|c[n]|·max|x| (every term's size).
double rounding_bound(const Eigen::VectorXd& c, const Eigen::VectorXd& x) {
  return 64.0 * 2.2e-16 * c.cwiseAbs().sum() * x.cwiseAbs().maxCoeff();
}

const FilterOrder kOrders[] = {FilterOrder::lowpass, FilterOrder::derivative1, FilterOrder::derivative2};

TEST(Fir, FullModeIsThePlainSumForEveryOrderAndLength) {
  for (int M : {2, 3, 5, 8, 41, 100}) {  // odd and even M: the kernels' tails of one, two and three taps
    const DifferentialFilter filter(FilterSettings{M, 0.3, 1e-3});
    const Eigen::VectorXd x = random_signal(2 * M + 1 + 700, static_cast<unsigned>(M));
    const Eigen::Index outputs = x.size() - 2 * M;
    for (FilterOrder order : kOrders) {
      const Eigen::VectorXd& c = filter.coefficients(order);
      Eigen::VectorXd y(outputs);
      detail::fir::correlate(order == FilterOrder::derivative1 ? Parity::antisymmetric : Parity::symmetric,
                             c.data() + M, M, x.data() + M, y.data(), outputs);
      const double bound = rounding_bound(c, x);
      for (Eigen::Index j = 0; j < outputs; ++j) ASSERT_NEAR(y[j], plain_sum(c, x, j), bound) << "M " << M << " j " << j;
    }
  }
}

TEST(Fir, FullModeThreeAtOnceIsEachAlone) {
  const int M = 37;
  const DifferentialFilter filter(FilterSettings{M, 0.12, 1e-3});
  const Eigen::VectorXd x = random_signal(3000, 7);
  const Eigen::Index outputs = x.size() - 2 * M;
  Eigen::VectorXd three[3] = {Eigen::VectorXd(outputs), Eigen::VectorXd(outputs), Eigen::VectorXd(outputs)};
  detail::fir::correlate_three(filter.coefficients(FilterOrder::lowpass).data() + M,
                               filter.coefficients(FilterOrder::derivative1).data() + M,
                               filter.coefficients(FilterOrder::derivative2).data() + M, M, x.data() + M,
                               three[0].data(), three[1].data(), three[2].data(), outputs);
  for (int k = 0; k < 3; ++k) {
    const Eigen::VectorXd& c = filter.coefficients(kOrders[k]);
    const double bound = rounding_bound(c, x);
    for (Eigen::Index j = 0; j < outputs; ++j) ASSERT_NEAR(three[k][j], plain_sum(c, x, j), bound) << "order " << k;
  }
}

// The strided mode is the full mode's every stride-th output, from any offset, for every band of
// the bank and for the second signal's low-pass; the bands do not disturb each other.
TEST(Fir, StridedModeIsEveryStrideThOutputOfTheFullMode) {
  for (int M : {2, 5, 30, 63}) {
    const std::vector<double> bands = {0.05, 0.2, 0.7};  // an odd count: the bank's pairs and its single
    std::vector<std::shared_ptr<const DifferentialFilter>> filters;
    std::vector<const DifferentialFilter*> pointers;
    for (double band : bands) filters.push_back(cached_filter(FilterSettings{M, band, 2e-3}));
    for (const auto& filter : filters) pointers.push_back(filter.get());
    const StridedBank bank(pointers);
    EXPECT_EQ(bank.half_length(), M);
    EXPECT_EQ(bank.bands(), 3);
    const Eigen::VectorXd x = random_signal(4000, 11u + static_cast<unsigned>(M));
    const Eigen::VectorXd y = random_signal(4000, 99u + static_cast<unsigned>(M));
    for (int stride : {1, 7, 16}) {
      for (int offset : {0, 3}) {
        const Eigen::Index outputs = DifferentialFilter::output_length(static_cast<int>(x.size()), M);
        const Eigen::Index rows = (outputs - offset + stride - 1) / stride;
        Eigen::MatrixXd O(rows + 2, 4 * bank.bands());  // a leading dimension larger than rows
        bank.apply(x.data() + offset, y.data() + offset, rows, stride, O.data(), O.rows());
        for (std::size_t g = 0; g < filters.size(); ++g) {
          Eigen::VectorXd full[3], lowpass_y(outputs);
          for (int k = 0; k < 3; ++k) full[k].resize(outputs);
          filters[g]->apply_all(x, full[0], full[1], full[2]);
          filters[g]->apply(FilterOrder::lowpass, y, lowpass_y);
          const Eigen::Index column = 4 * static_cast<Eigen::Index>(g);
          for (Eigen::Index r = 0; r < rows; ++r) {
            const Eigen::Index j = offset + r * stride;
            const auto bound = [&](FilterOrder order, const Eigen::VectorXd& signal) {
              return rounding_bound(filters[g]->coefficients(order), signal);
            };
            ASSERT_NEAR(O(r, column + 0), full[0][j], bound(FilterOrder::lowpass, x)) << "M " << M << " band " << g;
            ASSERT_NEAR(O(r, column + 1), full[2][j], bound(FilterOrder::derivative2, x)) << "M " << M;
            ASSERT_NEAR(O(r, column + 2), full[1][j], bound(FilterOrder::derivative1, x)) << "M " << M;
            ASSERT_NEAR(O(r, column + 3), lowpass_y[j], bound(FilterOrder::lowpass, y)) << "M " << M;
          }
        }
      }
    }
  }
}

TEST(Fir, StridedBankRefusesMixedHalfLengthsAndNoFilters) {
  const DifferentialFilter short_filter(FilterSettings{5, 0.2, 1e-3}), long_filter(FilterSettings{6, 0.2, 1e-3});
  EXPECT_THROW(StridedBank({&short_filter, &long_filter}), InputError);
  EXPECT_THROW(StridedBank(std::vector<const DifferentialFilter*>{}), InputError);
}

}  // namespace
}  // namespace manipid

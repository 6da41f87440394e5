// fir.cpp — the direct FIR sums of the differential filters, full and strided (fir.h).
#include "signal/fir.h"

#include "manipid/core/errors.h"
#include "manipid/core/signal/filters.h"

#include "vector_clones.h"

#include <algorithm>
#include <string>

namespace manipid::detail::fir {
namespace {

using Eigen::Index;

// Output blocks small enough that x's window and the outputs stay in L1 across all taps.
constexpr Index block_size = 512;

// The kernels are compiled for baseline x86-64 and for AVX2 (vector_clones.h). Vectorising
// across outputs keeps each output's operation order, so both versions agree bit for bit.

// y[j] = c[0] x[j] + Σ_{n=1}^{M} c[n] (x[j+n] + parity·x[j−n]) for j in [0, count), where
// `centre` points at the input the first output is centred on and `taps` at c[0] (the
// upper half of a symmetric or antisymmetric filter). Folding halves the multiplies; taps
// go in the outer loop so the inner loop over outputs is contiguous and vectorises (the
// dot-product order would need reassociation, which -O3 does not do); four taps per pass
// cut the loads and stores of y.
template <int parity>
[[gnu::always_inline]] inline void correlate_folded(const double* taps, int half_length,
                                                   const double* centre, double* out, Index count) {
  for (Index begin = 0; begin < count; begin += block_size) {
    const Index end = std::min(count, begin + block_size);
    const double c0 = parity > 0 ? taps[0] : 0.0;
    for (Index j = begin; j < end; ++j) out[j] = c0 * centre[j];
    int n = 1;
    for (; n + 3 <= half_length; n += 4) {
      const double a = taps[n], b = taps[n + 1], c = taps[n + 2], d = taps[n + 3];
      for (Index j = begin; j < end; ++j) {
        out[j] += (a * (centre[j + n] + parity * centre[j - n]) +
                   b * (centre[j + n + 1] + parity * centre[j - n - 1])) +
                  (c * (centre[j + n + 2] + parity * centre[j - n - 2]) +
                   d * (centre[j + n + 3] + parity * centre[j - n - 3]));
      }
    }
    for (; n <= half_length; ++n) {
      const double a = taps[n];
      for (Index j = begin; j < end; ++j) out[j] += a * (centre[j + n] + parity * centre[j - n]);
    }
  }
}

MANIPID_VECTOR_CLONES void correlate_symmetric(const double* taps, int half_length, const double* centre,
                                               double* out, Index count) {
  correlate_folded<+1>(taps, half_length, centre, out, count);
}

MANIPID_VECTOR_CLONES void correlate_antisymmetric(const double* taps, int half_length, const double* centre,
                                                   double* out, Index count) {
  correlate_folded<-1>(taps, half_length, centre, out, count);
}

// The three filters in one pass: the folded sum x[j+n] + x[j−n] serves lowpass and
// derivative2, the difference serves derivative1. Two taps per pass measured best here
// (three outputs already keep enough work in flight).
MANIPID_VECTOR_CLONES void correlate_folded_three(const double* lowpass, const double* derivative1, const double* derivative2,
                          int half_length, const double* centre, double* out0, double* out1, double* out2,
                          Index count) {
  for (Index begin = 0; begin < count; begin += block_size) {
    const Index end = std::min(count, begin + block_size);
    for (Index j = begin; j < end; ++j) {
      out0[j] = lowpass[0] * centre[j];
      out1[j] = 0.0;
      out2[j] = derivative2[0] * centre[j];
    }
    int n = 1;
    for (; n + 1 <= half_length; n += 2) {
      const double a0 = lowpass[n], a1 = derivative1[n], a2 = derivative2[n];
      const double b0 = lowpass[n + 1], b1 = derivative1[n + 1], b2 = derivative2[n + 1];
      const double *ahead_a = centre + n, *behind_a = centre - n;  // x[j+n], x[j−n]
      const double *ahead_b = ahead_a + 1, *behind_b = behind_a - 1;
      for (Index j = begin; j < end; ++j) {
        const double sum_a = ahead_a[j] + behind_a[j], difference_a = ahead_a[j] - behind_a[j];
        const double sum_b = ahead_b[j] + behind_b[j], difference_b = ahead_b[j] - behind_b[j];
        out0[j] += a0 * sum_a + b0 * sum_b;
        out1[j] += a1 * difference_a + b1 * difference_b;
        out2[j] += a2 * sum_a + b2 * sum_b;
      }
    }
    for (; n <= half_length; ++n) {
      const double a0 = lowpass[n], a1 = derivative1[n], a2 = derivative2[n];
      for (Index j = begin; j < end; ++j) {
        const double sum = centre[j + n] + centre[j - n], difference = centre[j + n] - centre[j - n];
        out0[j] += a0 * sum;
        out1[j] += a1 * difference;
        out2[j] += a2 * sum;
      }
    }
  }
}

// Four doubles: one AVX2 register (two SSE2 ones). GCC's loop vectoriser makes a poor job of
// filter_samples' loops (it vectorises the four sums across their lanes and reduces them at
// every step), so they are written on Lanes. A LanesAt is four doubles in memory, read or
// written in place whatever their alignment (may_alias: they are doubles).
using Lanes = double __attribute__((vector_size(32)));
using LanesAt = double __attribute__((vector_size(32), aligned(8), may_alias));
using LaneIndices = long long __attribute__((vector_size(32)));
[[gnu::always_inline]] inline LanesAt& lanes_at(double* at) { return *reinterpret_cast<LanesAt*>(at); }
[[gnu::always_inline]] inline const LanesAt& lanes_at(const double* at) { return *reinterpret_cast<const LanesAt*>(at); }

// The four sums of `B` bands (filter_samples) over one sample's folds, the bands' taps at
// `taps`, band b's at b·3K. Two bands at once keep eight sums running: one band's four are a
// chain of additions each, and wait on the adder's latency.
template <int B>
[[gnu::always_inline]] inline void band_sums(const double* taps, Eigen::Index K, const double* f0, const double* f1,
                                             const double* f2, double* out, Eigen::Index ld) {
  Lanes sums[B][4] = {};
  for (Eigen::Index i = 0; i < K; i += 4) {
    const Lanes even = lanes_at(f0 + i), odd = lanes_at(f1 + i), torque = lanes_at(f2 + i);
    for (int b = 0; b < B; ++b) {
      const double* c0 = taps + b * 3 * K;
      const Lanes lowpass = lanes_at(c0 + i);
      sums[b][0] += lowpass * even;
      sums[b][1] += lanes_at(c0 + 2 * K + i) * even;
      sums[b][2] += lanes_at(c0 + K + i) * odd;
      sums[b][3] += lowpass * torque;
    }
  }
  for (int b = 0; b < B; ++b) {
    for (int c = 0; c < 4; ++c) {
      const Lanes& sum = sums[b][c];
      out[(4 * b + c) * ld] = (sum[0] + sum[1]) + (sum[2] + sum[3]);
    }
  }
}

// Each band's four filters at each of `rows` thin samples of one joint: centre r·stride + M of
// q and of the torque signal (the reference when the torque is formed from it). Each sample's
// window is folded once, as the filters are (filters.cpp): f0[k] = q[c+k] + q[c−k] (q[c] at
// k = 0) meets the symmetric low-pass and second derivative, f1[k] = q[c+k] − q[c−k] (0 at
// k = 0) the antisymmetric first derivative, f2 the torque's like f0, which halves the work;
// the folds are contiguous, so every band's four sums over k stream through them four k at a
// time. `folds` holds 3·K doubles, K = M + 1 rounded up to a multiple of 4, zero past M (and
// so are the taps: `taps` holds band g's low-pass, first and second derivative at k = 0..K−1
// at g·3K, g·3K + K, g·3K + 2K). O is column-major with leading dimension `ld`, column 4g + c:
// c = 0 q, 1 q̈, 2 q̇, 3 the torque, low-passed. Each output is the same sum in the same order
// whichever bands share the call, so a band's values do not depend on the others.
MANIPID_VECTOR_CLONES void filter_samples(const double* q, const double* torque, Eigen::Index rows, Eigen::Index stride,
                                          Eigen::Index M, const double* taps, Eigen::Index bands, Eigen::Index K,
                                          double* folds, double* O, Eigen::Index ld) {
  const LaneIndices reversed = {3, 2, 1, 0};
  double* f0 = folds;
  double* f1 = folds + K;
  double* f2 = folds + 2 * K;
  for (Eigen::Index r = 0; r < rows; ++r) {
    const double* x = q + r * stride + M;  // the centre
    const double* y = torque + r * stride + M;
    f0[0] = x[0];
    f1[0] = 0.0;
    f2[0] = y[0];
    Eigen::Index k = 1;
    for (; k + 3 <= M; k += 4) {  // x[k..k+3] and x[−k..−k−3]
      const Lanes ahead = lanes_at(x + k), behind = __builtin_shuffle(Lanes(lanes_at(x - k - 3)), reversed);
      lanes_at(f0 + k) = ahead + behind;
      lanes_at(f1 + k) = ahead - behind;
      lanes_at(f2 + k) = lanes_at(y + k) + __builtin_shuffle(Lanes(lanes_at(y - k - 3)), reversed);
    }
    for (; k <= M; ++k) {
      f0[k] = x[k] + x[-k];
      f1[k] = x[k] - x[-k];
      f2[k] = y[k] + y[-k];
    }
    Eigen::Index g = 0;
    for (; g + 2 <= bands; g += 2) band_sums<2>(taps + g * 3 * K, K, f0, f1, f2, O + 4 * g * ld + r, ld);
    if (g < bands) band_sums<1>(taps + g * 3 * K, K, f0, f1, f2, O + 4 * g * ld + r, ld);
  }
}

}  // namespace

void correlate(Parity parity, const double* taps, int half_length, const double* centre, double* out, Index count) {
  if (parity == Parity::antisymmetric) {
    correlate_antisymmetric(taps, half_length, centre, out, count);
  } else {
    correlate_symmetric(taps, half_length, centre, out, count);
  }
}

void correlate_three(const double* lowpass, const double* derivative1, const double* derivative2, int half_length,
                     const double* centre, double* out0, double* out1, double* out2, Index count) {
  correlate_folded_three(lowpass, derivative1, derivative2, half_length, centre, out0, out1, out2, count);
}

StridedBank::StridedBank(const std::vector<const DifferentialFilter*>& filters) {
  if (filters.empty()) throw InputError("filters", "a strided filter bank needs at least one filter");
  half_length_ = filters.front()->settings().half_length;
  bands_ = static_cast<Index>(filters.size());
  padded_ = (half_length_ + 1 + 3) / 4 * 4;
  taps_.assign(static_cast<std::size_t>(bands_ * 3 * padded_), 0.0);
  double* tap = taps_.data();
  for (const DifferentialFilter* filter : filters) {
    if (filter->settings().half_length != half_length_) {
      throw InputError("filters", "a strided filter bank's filters share one half-length: " + std::to_string(half_length_) +
                                      " and " + std::to_string(filter->settings().half_length));
    }
    for (FilterOrder order : {FilterOrder::lowpass, FilterOrder::derivative1, FilterOrder::derivative2}) {
      // The taps at k = 0..M of the (2M + 1)-long filter, centre M; the first derivative's centre
      // tap is 0 and meets the zero fold.
      const Eigen::VectorXd& c = filter->coefficients(order);
      for (int k = 0; k <= half_length_; ++k) tap[k] = c[half_length_ + k];
      tap += padded_;
    }
  }
}

void StridedBank::apply(const double* x, const double* y, Index rows, Index stride, double* O, Index ld) const {
  thread_local std::vector<double> folds;
  folds.assign(static_cast<std::size_t>(3 * padded_), 0.0);
  filter_samples(x, y, rows, stride, half_length_, taps_.data(), bands_, padded_, folds.data(), O, ld);
}

}  // namespace manipid::detail::fir

// fir.h — the one engine for direct FIR sums of the differential filters: every output (full mode) or every stride-th (strided mode).
//
// Both modes fold a symmetric window: y[c] = t[0] x[c] + Σ_{k=1}^{M} t[k] (x[c+k] ± x[c−k]), the
// sum for the symmetric low-pass and second derivative, the difference for the antisymmetric first
// derivative, which halves the multiplies. They differ in which loop is inside:
// - full mode (`correlate`, `correlate_three`): every output j in [0, count); taps outside,
//   outputs inside, so the inner loop is contiguous over outputs and vectorises;
// - strided mode (`StridedBank`): a few outputs far apart (the filter choice's thin samples);
//   outputs outside, taps inside, each output's window folded once and met by every filter of
//   several bands.
// The two sum in different orders, so they agree to rounding, not bit for bit (a few ulps of
// Σ|t[k]|·max|x|; tests/core/fir_test.cpp). Long filters go through the FFT instead (filters.cpp).
// Every kernel is compiled for baseline x86-64 and AVX2 (vector_clones.h), bit-identical.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace manipid {
class DifferentialFilter;
}

namespace manipid::detail::fir {

/// The filter's symmetry: +1 symmetric (low-pass, second derivative), −1 antisymmetric (first derivative).
enum class Parity { symmetric = +1, antisymmetric = -1 };

/// Full mode, one filter: out[j] = t[0] c[j] + Σ_{k=1}^{M} t[k] (c[j+k] ± c[j−k]), j in [0, count),
/// where `centre` points at the input the first output is centred on and `taps` at t[0] (the
/// upper half of the filter, M + 1 values). Reads centre[−M .. count − 1 + M].
void correlate(Parity parity, const double* taps, int half_length, const double* centre, double* out,
               Eigen::Index count);

/// Full mode, the three differential filters at once (the low-pass and second derivative share
/// the fold's sums, the first derivative its differences); each output as `correlate` would give
/// it to rounding.
void correlate_three(const double* lowpass, const double* derivative1, const double* derivative2, int half_length,
                     const double* centre, double* out0, double* out1, double* out2, Eigen::Index count);

/// Strided mode: the three filters of several bands (all of one half-length M) at every
/// `stride`-th output of a signal x, and the low-pass of a second signal y (the torque) at the
/// same outputs. Output r is centred on input r·stride + M of the pointers given (so a caller
/// starting at sample `first` passes x + first). Built once per set of filters, applied per joint.
class StridedBank {
 public:
  /// The filters, all of the same half-length (InputError otherwise); at least one.
  explicit StridedBank(const std::vector<const DifferentialFilter*>& filters);

  int half_length() const { return half_length_; }
  Eigen::Index bands() const { return bands_; }

  /// O (column-major, leading dimension `ld` ≥ rows, 4·bands() columns) gets at row r, for band
  /// g: column 4g x low-passed, 4g + 1 its second derivative, 4g + 2 its first derivative,
  /// 4g + 3 y low-passed. Reads x and y at [0, (rows − 1)·stride + 2M].
  void apply(const double* x, const double* y, Eigen::Index rows, Eigen::Index stride, double* O,
             Eigen::Index ld) const;

 private:
  int half_length_ = 0;
  Eigen::Index bands_ = 0;
  Eigen::Index padded_ = 0;  // K: M + 1 rounded up to a multiple of 4 (the taps and folds are zero past M)
  std::vector<double> taps_;  // band g's low-pass, first and second derivative at k = 0..K−1 at g·3K, +K, +2K
};

}  // namespace manipid::detail::fir

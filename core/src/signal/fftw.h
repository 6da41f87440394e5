// fftw.h — the one FFT facade: FFTW's complex transforms, planned once per length, serving the long filters' real transforms.
//
// FFTW (Debian's libfftw3-double3) does a real transform of 4,096 points ~4× faster than Eigen's
// kissfft. It is linked normally: loading it costs a process ~0.7 ms at start (an empty program
// with and without -lfftw3: 0.86 against 1.57 ms), about 4 % of a whole `manipid identify` on the
// paper's run, which no user sees — it was loaded at first use until that was measured.
#pragma once

#include <fftw3.h>

#include <Eigen/Core>

#include <complex>
#include <cstddef>
#include <new>
#include <vector>

namespace manipid::detail {

/// An array FFTW may work on: from fftw_malloc, so every one has the alignment the plans were
/// made with (FFTW's condition for executing a plan on other arrays than its own).
template <typename T>
class FftwArray {
 public:
  FftwArray() = default;
  explicit FftwArray(Eigen::Index size) { resize(size); }
  FftwArray(const FftwArray&) = delete;
  FftwArray& operator=(const FftwArray&) = delete;
  ~FftwArray() {
    if (data_) fftw_free(data_);
  }
  /// Holds at least `size` elements afterwards; the contents are not kept.
  void resize(Eigen::Index size) {
    if (size <= capacity_) return;
    if (data_) fftw_free(data_);
    data_ = static_cast<T*>(fftw_malloc(sizeof(T) * static_cast<std::size_t>(size)));
    if (!data_) throw std::bad_alloc();
    capacity_ = size;
  }
  T* data() const { return data_; }

 private:
  T* data_ = nullptr;
  Eigen::Index capacity_ = 0;
};

/// The real transforms of one length B (a multiple of 4): forward, B reals to the B/2 + 1
/// complex values of the half spectrum; backward, the half spectrum to B reals, B times the
/// inverse transform (unnormalised, as FFTW's c2r). Both are done by one complex transform of
/// B/2 points (the reals read as B/2 complex numbers, even samples the real parts) and a
/// twiddle pass that splits or joins the even and odd halves' spectra. FFTW's own r2c/c2r
/// transforms run a little faster (all three filters at M = 400: 0.22 against 0.26 ms), but
/// FFTW_ESTIMATE plans them in ~2 ms a pair here against ~0.05 ms for the complex pair (after
/// the planner's first plan, ~0.4 ms, which either pays): a cost every one-shot command that
/// filters with a long window paid once, against ~0.04 ms more a job in a service.
/// Made once per length under a lock (FFTW's planner is not thread-safe; executing a plan is)
/// and kept for the process's life.
class RealTransforms {
 public:
  static const RealTransforms& of_length(Eigen::Index length);

  /// `in` (B reals, kept) to `out` (B/2 + 1); both FftwArrays.
  void forward(double* in, fftw_complex* out) const;
  /// `in` (B/2 + 1, overwritten; the imaginary parts of its first and last value are taken as
  /// 0, as a real signal's are) to `out` (B reals); both FftwArrays.
  void backward(fftw_complex* in, double* out) const;

 private:
  RealTransforms() = default;
  Eigen::Index half_ = 0;                     // N = B/2, the complex transforms' length
  fftw_plan forward_ = nullptr, backward_ = nullptr;
  std::vector<std::complex<double>> twiddle_;  // exp(−2πik/B), k = 0 … N/2
};

}  // namespace manipid::detail

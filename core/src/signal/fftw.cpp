// fftw.cpp — real transforms of one length from one complex pair of FFTW plans, made once per length (fftw.h).
#include "signal/fftw.h"

#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>

namespace manipid::detail {

const RealTransforms& RealTransforms::of_length(Eigen::Index length) {
  if (length < 4 || length % 4 != 0) throw std::invalid_argument("real transforms need a length divisible by 4, got " + std::to_string(length));
  static std::mutex planning;
  // Never freed, nor are the plans: they serve until the process ends (and a map destroyed at
  // exit would leave FFTW's plans unreachable, which LeakSanitizer reports).
  static auto* const made = new std::map<Eigen::Index, std::unique_ptr<RealTransforms>>();
  const std::lock_guard<std::mutex> lock(planning);
  std::unique_ptr<RealTransforms>& slot = (*made)[length];
  if (!slot) {
    const Eigen::Index half = length / 2;
    // FFTW_ESTIMATE: plans without running trial transforms on the arrays (FFTW_MEASURE would
    // take tens of milliseconds per length to gain a little per call). Out of place, as run.
    const FftwArray<fftw_complex> a(half + 1), b(half + 1);
    const int n = static_cast<int>(half);
    auto transforms = std::unique_ptr<RealTransforms>(new RealTransforms());
    transforms->half_ = half;
    transforms->forward_ = fftw_plan_dft_1d(n, a.data(), b.data(), FFTW_FORWARD, FFTW_ESTIMATE);
    transforms->backward_ = fftw_plan_dft_1d(n, a.data(), b.data(), FFTW_BACKWARD, FFTW_ESTIMATE | FFTW_DESTROY_INPUT);
    if (!transforms->forward_ || !transforms->backward_) throw std::runtime_error("FFTW made no plan for a transform of length " + std::to_string(length));
    transforms->twiddle_.resize(static_cast<std::size_t>(half / 2 + 1));
    const double step = -2.0 * std::numbers::pi / static_cast<double>(length);
    for (std::size_t k = 0; k < transforms->twiddle_.size(); ++k) transforms->twiddle_[k] = std::polar(1.0, step * static_cast<double>(k));
    slot = std::move(transforms);
  }
  return *slot;
}

// With z[m] = x[2m] + i·x[2m+1] and Z its N-point transform, the even and odd samples'
// transforms are E[k] = (Z[k] + conj Z[N−k]) / 2 and O[k] = (Z[k] − conj Z[N−k]) / 2i, and
// X[k] = E[k] + W^k O[k], X[N−k] = conj(E[k] − W^k O[k]) with W = exp(−2πi/B): each pair
// (k, N−k) is formed from the same two values, so the pass runs in place.
void RealTransforms::forward(double* in, fftw_complex* out) const {
  fftw_execute_dft(forward_, reinterpret_cast<fftw_complex*>(in), out);
  const Eigen::Index n = half_;
  const double z0_re = out[0][0], z0_im = out[0][1];
  out[0][0] = z0_re + z0_im;
  out[0][1] = 0.0;
  out[n][0] = z0_re - z0_im;
  out[n][1] = 0.0;
  for (Eigen::Index k = 1; k <= n / 2; ++k) {
    const double a_re = out[k][0], a_im = out[k][1], b_re = out[n - k][0], b_im = out[n - k][1];
    const double e_re = 0.5 * (a_re + b_re), e_im = 0.5 * (a_im - b_im);
    const double o_re = 0.5 * (a_im + b_im), o_im = -0.5 * (a_re - b_re);
    const std::complex<double> w = twiddle_[static_cast<std::size_t>(k)];
    const double wo_re = w.real() * o_re - w.imag() * o_im, wo_im = w.real() * o_im + w.imag() * o_re;
    out[k][0] = e_re + wo_re;
    out[k][1] = e_im + wo_im;
    out[n - k][0] = e_re - wo_re;
    out[n - k][1] = -(e_im - wo_im);
  }
}

// The join, inverse of the split above and twice it (so the N-point backward transform gives
// B·x, as FFTW's c2r): Z[k] = E[k] + i·O[k] with E[k] = X[k] + conj X[N−k] and
// O[k] = (X[k] − conj X[N−k]) · conj W^k; Z[N−k] = conj E[k] + i·conj O[k].
void RealTransforms::backward(fftw_complex* in, double* out) const {
  const Eigen::Index n = half_;
  const double x0 = in[0][0], xn = in[n][0];
  in[0][0] = x0 + xn;
  in[0][1] = x0 - xn;
  for (Eigen::Index k = 1; k <= n / 2; ++k) {
    const double a_re = in[k][0], a_im = in[k][1], b_re = in[n - k][0], b_im = in[n - k][1];
    const double e_re = a_re + b_re, e_im = a_im - b_im;
    const double d_re = a_re - b_re, d_im = a_im + b_im;
    const std::complex<double> w = twiddle_[static_cast<std::size_t>(k)];
    const double o_re = d_re * w.real() + d_im * w.imag(), o_im = d_im * w.real() - d_re * w.imag();
    in[k][0] = e_re - o_im;
    in[k][1] = e_im + o_re;
    in[n - k][0] = e_re + o_im;
    in[n - k][1] = -e_im + o_re;
  }
  fftw_execute_dft(backward_, in, reinterpret_cast<fftw_complex*>(out));
}

}  // namespace manipid::detail

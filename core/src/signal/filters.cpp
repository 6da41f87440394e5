// filters.cpp — the paper's differential filters (filters.h): coefficient design after
// Cedro & Janecki, section 3 (`Filtr` → lowpass, `Filtr1` → derivative1, `Filtr2` →
// derivative2), a fast 'valid' FIR application, and a process-wide cache of built filters.
#include "manipid/core/signal/filters.h"

#include "manipid/core/errors.h"

#include "signal/fftw.h"
#include "signal/fir.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace manipid {
namespace {

using Eigen::Index;

// Keeps 2M + 1 and N − 2M − 1 far from int overflow (and the taps at a few tens of MB).
constexpr int max_half_length = 1'000'000;
// Distinct settings kept by cached_filter(); a service fed arbitrary settings must not grow
// without bound. Filters already handed out stay alive through their shared_ptr.
constexpr std::size_t max_cached_filters = 256;

// The ideal responses as integrals over u = Ω/Ωg ∈ [0, 1], x = Ωg·n:
//   s0(x) = ∫₀¹ cos(xu) du    = sin x / x
//   s1(x) = ∫₀¹ u sin(xu) du  = (sin x − x cos x) / x²
//   s2(x) = ∫₀¹ u² cos(xu) du = (x² sin x + 2x cos x − 2 sin x) / x³
// so that h0[n] = (Ωg/π) s0, h1[n] = −Ωg²/(πΔ) s1, h2[n] = −Ωg³/(πΔ²) s2. The closed forms
// cancel catastrophically for small x, where the (fast-converging) Taylor series is used.
constexpr double series_limit = 1.0;
constexpr int series_terms = 12;  // |x| < 1: the first omitted term is below 1e-25

double s0(double x) {
  if (std::abs(x) >= series_limit) return std::sin(x) / x;
  double sum = 0.0, power = 1.0, factorial = 1.0;  // power = x^{2k}, factorial = (2k+1)!
  for (int k = 0; k < series_terms; ++k) {
    sum += power / factorial;
    power *= -x * x;
    factorial *= (2.0 * k + 2.0) * (2.0 * k + 3.0);
  }
  return sum;
}

double s1(double x) {
  if (std::abs(x) >= series_limit) return (std::sin(x) - x * std::cos(x)) / (x * x);
  double sum = 0.0, power = x, factorial = 1.0;  // power = x^{2k+1}, factorial = (2k+1)!
  for (int k = 0; k < series_terms; ++k) {
    sum += power / (factorial * (2.0 * k + 3.0));
    power *= -x * x;
    factorial *= (2.0 * k + 2.0) * (2.0 * k + 3.0);
  }
  return sum;
}

// r(x) = s2(x) − s0(x)/3 = −2x²/45 + …: h2 with its O(1) constant part taken out. Filtr2
// removes the DC gain of h2·w with the low-pass (h2w − xH3·h0FH); doing that on r instead of
// s2 is algebraically identical but keeps the result accurate when Ωg·M is small, where the
// paper's form loses ~(Ωg·M)² of its precision to cancellation.
double r2(double x) {
  if (std::abs(x) >= series_limit) {
    const double s = std::sin(x), c = std::cos(x);
    return (x * x * s + 2.0 * x * c - 2.0 * s) / (x * x * x) - s / (3.0 * x);
  }
  // Coefficient of (−1)^k x^{2k}: 1/((2k)!(2k+3)) − 1/(3(2k+1)!) = 4k / (3 (2k+1)! (2k+3)).
  double sum = 0.0, power = -x * x, factorial = 6.0;  // power = (−1)^k x^{2k}, factorial = (2k+1)!
  for (int k = 1; k < series_terms; ++k) {
    sum += power * (4.0 * k) / (3.0 * factorial * (2.0 * k + 3.0));
    power *= -x * x;
    factorial *= (2.0 * k + 2.0) * (2.0 * k + 3.0);
  }
  return sum;
}

// The paper's "Harris" window (its own rounded coefficients, not Blackman–Harris's).
double harris_window(int n, int half_length) {
  const double phase = std::numbers::pi * n / half_length;
  return 0.36 + 0.49 * std::cos(phase) + 0.14 * std::cos(2.0 * phase) + 0.01 * std::cos(3.0 * phase);
}

// Builds the full 2M + 1 taps from n = 0..M, mirrored so that (anti)symmetry is exact; the
// folded kernels below rely on it.
Eigen::VectorXd mirrored(const std::vector<double>& half, int half_length, double parity) {
  Eigen::VectorXd taps(2 * half_length + 1);
  for (int n = 0; n <= half_length; ++n) {
    taps[half_length + n] = half[n];
    taps[half_length - n] = parity * half[n];
  }
  if (parity < 0) taps[half_length] = 0.0;
  return taps;
}

// Long filters through the FFT, by overlap-save: blocks of B inputs (B a power of two, at least
// 4(2M + 1), so a block yields B − 2M ≥ 3/4 B outputs) are transformed once, multiplied by
// each filter's conjugate spectrum (a correlation, as the direct sum), and transformed back;
// the first B − 2M outputs of a block are free of wrap-around. A direct output costs ~M
// multiply-adds; an FFT output ~4(log₂ B)/(1 − 2M/B) operations whatever M is. The transforms
// are FFTW's (fftw.h).
// B is at least 4,096, one length for every M up to 511: FFTW plans each new length once per
// process (fftw.h: ~0.05 ms a length after its first plan), and for M = 100 a block of 4,096 costs
// per output what one of 1,024 does. Rounding differs from the direct sum's, not its size:
// both are a few ulps of Σ|c[n]|·max|x| (tests/core/filters_test.cpp compares the two).
Index fft_block_length(int half_length) {
  Index length = 4096;
  while (length < 4 * (2 * static_cast<Index>(half_length) + 1)) length *= 2;
  return length;
}

// The FFT path pays when the filter is long and there is at least a block's worth of outputs.
bool use_fft(int half_length, Index outputs) {
  return half_length >= DifferentialFilter::fft_min_half_length && half_length <= DifferentialFilter::fft_max_half_length &&
         outputs >= fft_block_length(half_length) - 2 * static_cast<Index>(half_length);
}

bool overlaps(const double* a, Index a_size, const double* b, Index b_size) {
  return std::less<>{}(a, b + b_size) && std::less<>{}(b, a + a_size);
}

}  // namespace

void FilterSettings::validate() const {
  if (half_length < 2 || half_length > max_half_length) {
    throw InputError("half_length", "filter half-length M must be between 2 and " +
                                        std::to_string(max_half_length) + ", got " +
                                        std::to_string(half_length));
  }
  validate_band(band);
  if (!(dt > 0.0 && std::isfinite(dt))) {
    throw InputError("dt", "sample period dt must be positive and finite, got " + std::to_string(dt));
  }
}

DifferentialFilter::DifferentialFilter(const FilterSettings& settings) : settings_(settings) {
  settings_.validate();
  const int m = settings_.half_length;
  const double band = settings_.band, dt = settings_.dt, pi = std::numbers::pi;

  // Windowed ideal responses for n = 0..M (the rest follows by symmetry).
  std::vector<double> window(m + 1), h0w(m + 1), h1w(m + 1), r2w(m + 1);
  for (int n = 0; n <= m; ++n) {
    window[n] = harris_window(n, m);
    const double x = band * n;
    h0w[n] = band / pi * s0(x) * window[n];
    h1w[n] = -band * band / (pi * dt) * s1(x) * window[n];
    r2w[n] = -band * band * band / (pi * dt * dt) * r2(x) * window[n];
  }
  // Σ_{n=−M}^{M} f(n) for f even in n, from n ≥ 0 (small edge taps first).
  auto symmetric_sum = [m](auto&& term) {
    double sum = 0.0;
    for (int n = m; n >= 1; --n) sum += 2.0 * term(n);  // small edge taps first
    return sum + term(0);
  };

  // Filtr: h0p = h0·w / xH1, xH1 = Σ h0·w (unit DC gain).
  const double lowpass_gain = symmetric_sum([&](int n) { return h0w[n]; });
  std::vector<double> lowpass(m + 1), derivative1(m + 1), derivative2(m + 1);
  for (int n = 0; n <= m; ++n) lowpass[n] = h0w[n] / lowpass_gain;

  // Filtr1: h1p = h1·w·(−1/xH2), xH2 = Σ h1·w·(0 − nΔ), i.e. Σ c1[n]·nΔ = 1: with
  // y[i] = Σ c[n] x[i+n] a ramp of slope v gives exactly v.
  const double ramp_gain = symmetric_sum([&](int n) { return h1w[n] * n * dt; });
  for (int n = 0; n <= m; ++n) derivative1[n] = h1w[n] / ramp_gain;

  // Filtr2: g = h2·w − xH3·h0FH (xH3 = Σ h2·w, h0FH the normalised low-pass), then
  // h2p = −2/xH4·g with xH4 = Σ g·(−(nΔ)²), i.e. Σ c2[n]·(nΔ)² = 2 and Σ c2[n] = 0.
  // With h2 = −Ωg³/(πΔ²)·(s0/3 + r2), the s0/3 part is a multiple of h0 and drops out of g.
  const double r2_gain = symmetric_sum([&](int n) { return r2w[n]; });
  std::vector<double> dc_free(m + 1);
  for (int n = 0; n <= m; ++n) dc_free[n] = r2w[n] - r2_gain * lowpass[n];
  const double parabola_gain = symmetric_sum([&](int n) { return dc_free[n] * (n * dt) * (n * dt); });
  for (int n = 0; n <= m; ++n) derivative2[n] = 2.0 * dc_free[n] / parabola_gain;

  lowpass_ = mirrored(lowpass, m, +1.0);
  derivative1_ = mirrored(derivative1, m, -1.0);
  derivative2_ = mirrored(derivative2, m, +1.0);
}

const Eigen::VectorXd& DifferentialFilter::coefficients(FilterOrder order) const {
  switch (order) {
    case FilterOrder::lowpass: return lowpass_;
    case FilterOrder::derivative1: return derivative1_;
    case FilterOrder::derivative2: return derivative2_;
  }
  throw std::invalid_argument("unknown filter order " + std::to_string(static_cast<int>(order)));
}

int DifferentialFilter::checked_output_length(int input_samples) const {
  const int m = settings_.half_length;
  const int outputs = output_length(input_samples);
  if (outputs < 1) {
    throw InputError("samples", "the differential filter with half-length M = " + std::to_string(m) +
                                    " needs at least 2M+2 = " + std::to_string(min_input_samples(m)) +
                                    " samples, got " + std::to_string(input_samples));
  }
  return outputs;
}

namespace {

void check_output_size(Index expected, Index actual, const char* name) {
  if (expected != actual) {
    throw std::invalid_argument(std::string("filter output '") + name + "' has " + std::to_string(actual) +
                                " entries, expected " + std::to_string(expected));
  }
}

}  // namespace

struct DifferentialFilter::Spectra {
  Index block = 0;  // B
  const detail::RealTransforms* transforms = nullptr;  // FFTW's plans for B
  // By FilterOrder: conj(FFT of the taps padded to B) / B, the 1/B of the inverse transform folded in.
  std::array<std::vector<std::complex<double>>, 3> of;
};

const DifferentialFilter::Spectra& DifferentialFilter::spectra() const {
  std::call_once(spectra_once_, [this] {
    auto made = std::make_shared<Spectra>();
    made->block = fft_block_length(settings_.half_length);
    made->transforms = &detail::RealTransforms::of_length(made->block);
    const detail::RealTransforms& transforms = *made->transforms;
    const Index bins = made->block / 2 + 1;
    detail::FftwArray<double> padded(made->block);
    detail::FftwArray<fftw_complex> spectrum(bins);
    const double scale = 1.0 / static_cast<double>(made->block);
    for (const FilterOrder order : {FilterOrder::lowpass, FilterOrder::derivative1, FilterOrder::derivative2}) {
      const Eigen::VectorXd& taps = coefficients(order);
      std::fill(padded.data(), padded.data() + made->block, 0.0);
      std::copy(taps.data(), taps.data() + taps.size(), padded.data());
      transforms.forward(padded.data(), spectrum.data());
      auto& of = made->of[static_cast<std::size_t>(order)];
      of.resize(static_cast<std::size_t>(bins));
      for (Index i = 0; i < bins; ++i) of[static_cast<std::size_t>(i)] = std::complex<double>(spectrum.data()[i][0], -spectrum.data()[i][1]) * scale;
    }
    spectra_ = std::move(made);
  });
  return *spectra_;
}

namespace {

// y_k[j] = Σ_n c_k[n] x[j + M + n], j < outputs, for the orders asked (null outputs are skipped).
void correlate_by_fft(int half_length, const std::array<const std::vector<std::complex<double>>*, 3>& spectra,
                      const detail::RealTransforms& transforms, Index block, const double* x, Index samples,
                      const std::array<double*, 3>& outputs, Index count) {
  const Index step = block - 2 * static_cast<Index>(half_length);
  const Index bins = block / 2 + 1;
  // Per thread, grown to the longest block seen: FFTW executes a plan on any arrays aligned as
  // the planner's, which fftw_malloc's are.
  thread_local detail::FftwArray<double> input, output;
  thread_local detail::FftwArray<fftw_complex> transform, product;
  input.resize(block);
  output.resize(block);
  transform.resize(bins);
  product.resize(bins);
  for (Index first = 0; first < count; first += step) {
    const Index available = std::min(block, samples - first);
    std::copy(x + first, x + first + available, input.data());
    std::fill(input.data() + available, input.data() + block, 0.0);
    transforms.forward(input.data(), transform.data());
    const Index kept = std::min(step, count - first);
    for (std::size_t k = 0; k < 3; ++k) {
      if (!outputs[k]) continue;
      // The complex product written out: std::complex's operator* checks every result for NaN
      // (C99 Annex G), which keeps the loop from vectorising.
      const double* taps = reinterpret_cast<const double*>(spectra[k]->data());  // [re, im] pairs
      const double* in = transform.data()[0];
      double* out = product.data()[0];
      for (Index i = 0; i < 2 * bins; i += 2) {
        out[i] = in[i] * taps[i] - in[i + 1] * taps[i + 1];
        out[i + 1] = in[i] * taps[i + 1] + in[i + 1] * taps[i];
      }
      transforms.backward(product.data(), output.data());
      std::copy(output.data(), output.data() + kept, outputs[k] + first);
    }
  }
}

}  // namespace

bool DifferentialFilter::uses_fft(int input_samples) const {
  return use_fft(settings_.half_length, output_length(input_samples));
}

void DifferentialFilter::apply(FilterOrder order, const Eigen::Ref<const Eigen::VectorXd>& x,
                               Eigen::Ref<Eigen::VectorXd> y) const {
  apply(order, x, y, true);
}

void DifferentialFilter::apply_direct(FilterOrder order, const Eigen::Ref<const Eigen::VectorXd>& x,
                                      Eigen::Ref<Eigen::VectorXd> y) const {
  apply(order, x, y, false);
}

void DifferentialFilter::apply(FilterOrder order, const Eigen::Ref<const Eigen::VectorXd>& x,
                               Eigen::Ref<Eigen::VectorXd> y, bool fft_allowed) const {
  const Index outputs = checked_output_length(static_cast<int>(x.size()));
  check_output_size(outputs, y.size(), "y");
  const Eigen::VectorXd& taps = coefficients(order);
  const int m = settings_.half_length;

  // The kernel writes y while still reading x; an overlapping y gets a private copy of x.
  Eigen::VectorXd copy;
  const double* input = x.data();
  if (overlaps(x.data(), x.size(), y.data(), y.size())) input = (copy = x).data();

  if (fft_allowed && use_fft(m, outputs)) {
    const Spectra& fft = spectra();
    std::array<const std::vector<std::complex<double>>*, 3> chosen{};
    std::array<double*, 3> out{};
    chosen[static_cast<std::size_t>(order)] = &fft.of[static_cast<std::size_t>(order)];
    out[static_cast<std::size_t>(order)] = y.data();
    correlate_by_fft(m, chosen, *fft.transforms, fft.block, input, x.size(), out, outputs);
    return;
  }
  detail::fir::correlate(order == FilterOrder::derivative1 ? detail::fir::Parity::antisymmetric : detail::fir::Parity::symmetric,
                         taps.data() + m, m, input + m, y.data(), outputs);
}

Eigen::VectorXd DifferentialFilter::apply(FilterOrder order, const Eigen::Ref<const Eigen::VectorXd>& x) const {
  Eigen::VectorXd y(checked_output_length(static_cast<int>(x.size())));
  apply(order, x, y);
  return y;
}

void DifferentialFilter::apply_all(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> lowpass,
                                   Eigen::Ref<Eigen::VectorXd> derivative1,
                                   Eigen::Ref<Eigen::VectorXd> derivative2) const {
  const Index outputs = checked_output_length(static_cast<int>(x.size()));
  check_output_size(outputs, lowpass.size(), "lowpass");
  check_output_size(outputs, derivative1.size(), "derivative1");
  check_output_size(outputs, derivative2.size(), "derivative2");
  const int m = settings_.half_length;

  Eigen::VectorXd copy;
  const double* input = x.data();
  if (overlaps(x.data(), x.size(), lowpass.data(), outputs) ||
      overlaps(x.data(), x.size(), derivative1.data(), outputs) ||
      overlaps(x.data(), x.size(), derivative2.data(), outputs)) {
    input = (copy = x).data();
  }
  if (use_fft(m, outputs)) {
    const Spectra& fft = spectra();
    correlate_by_fft(m, {&fft.of[0], &fft.of[1], &fft.of[2]}, *fft.transforms, fft.block, input, x.size(),
                     {lowpass.data(), derivative1.data(), derivative2.data()}, outputs);
    return;
  }
  detail::fir::correlate_three(lowpass_.data() + m, derivative1_.data() + m, derivative2_.data() + m, m, input + m,
                               lowpass.data(), derivative1.data(), derivative2.data(), outputs);
}

std::complex<double> DifferentialFilter::frequency_response(FilterOrder order, double omega) const {
  // Σ_n c[n] e^{iΩn} folded by symmetry: 2Σ c[n] cos(Ωn) (+ c[0]) for the symmetric filters,
  // 2iΣ c[n] sin(Ωn) for derivative1 — exactly real / imaginary, as the ideal responses.
  const Eigen::VectorXd& taps = coefficients(order);
  const int m = settings_.half_length;
  double sum = 0.0;
  if (order == FilterOrder::derivative1) {
    for (int n = m; n >= 1; --n) sum += 2.0 * taps[m + n] * std::sin(omega * n);
    return {0.0, sum};
  }
  for (int n = m; n >= 1; --n) sum += 2.0 * taps[m + n] * std::cos(omega * n);
  return {sum + taps[m], 0.0};
}

std::shared_ptr<const DifferentialFilter> cached_filter(const FilterSettings& settings) {
  using Key = std::tuple<int, double, double>;
  static std::mutex mutex;
  static std::map<Key, std::shared_ptr<const DifferentialFilter>> cache;

  settings.validate();  // first: a NaN key would break the map's ordering
  const Key key{settings.half_length, settings.band, settings.dt};
  {
    std::lock_guard lock(mutex);
    if (auto found = cache.find(key); found != cache.end()) return found->second;
  }
  // Built outside the lock (it validates, and may take a while for long filters); if
  // another thread got there first, its filter wins so equal settings share one object.
  auto filter = std::make_shared<const DifferentialFilter>(settings);
  std::lock_guard lock(mutex);
  if (auto found = cache.find(key); found != cache.end()) return found->second;
  if (cache.size() >= max_cached_filters) cache.erase(cache.begin());
  cache.emplace(key, filter);
  return filter;
}

}  // namespace manipid

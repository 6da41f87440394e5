// filters.h — the paper's differential filters: windowed, band-limited FIR filters that
// low-pass a sampled signal and, optionally, differentiate it once or twice.
//
// The ideal response of order k is (iΩ/Δ)^k for |Ω| ≤ Ωg and 0 beyond (Ω in rad/sample);
// its inverse Fourier transform is truncated to n = −M..M and multiplied by the paper's
// Harris window w(n) = 0.36 + 0.49 cos(nπ/M) + 0.14 cos(2nπ/M) + 0.01 cos(3nπ/M). Then,
// as in the paper:
//   order 0 (`Filtr`,  lowpass):     scaled to unit DC gain;
//   order 1 (`Filtr1`, derivative1): scaled so that a ramp gives its slope exactly;
//   order 2 (`Filtr2`, derivative2): its DC gain removed with the normalised low-pass, then
//                                    scaled so that t² gives exactly 2.
// The output is the 'valid' part: for N input samples, N − 2M − 1 outputs, output j
// (0-based) centred on input sample M + j, i.e. 1-based inputs M+1..N−M−1 as in the paper.
// (The paper's loop stops one sample short of the last full window; we keep its length.)
#pragma once

#include "manipid/core/errors.h"

#include <Eigen/Core>

#include <complex>
#include <memory>
#include <cstdio>
#include <numbers>
#include <mutex>
#include <string>

namespace manipid {

enum class FilterOrder { lowpass = 0, derivative1 = 1, derivative2 = 2 };

/// The narrowest band edge accepted, rad/sample: below it the coefficients (∝ band³ for q̈) underflow.
inline constexpr double kMinBand = 1e-9;

/// Throws InputError(field) unless band (rad/sample) lies in [kMinBand, π]: FilterSettings::validate's
/// rule for the band, for callers that check a request before a filter exists (inline: the parsers'
/// fuzz targets link no filter code).
inline void validate_band(double band, const std::string& field = "band") {
  if (!(band > 0.0 && band <= std::numbers::pi)) {  // also rejects NaN
    throw InputError(field, "filter band edge must be in (0, pi] rad/sample, got " + std::to_string(band));
  }
  // The coefficients scale with band, band² and band³ before they are normalised: far below any
  // motion's band they underflow to 0 (band 1e-300 made every derivative NaN, and the identification
  // then failed naming the first parameter as if its value were wrong).
  if (band < kMinBand) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "filter band edge %.3g rad/sample is below %g, where the filters' coefficients underflow (at dt = "
                  "1 ms that is a period of %.0f days): give a band that passes the motion",
                  band, kMinBand, 2.0 * std::numbers::pi / kMinBand * 1e-3 / 86400.0);
    throw InputError(field, text);
  }
}

struct FilterSettings {
  int half_length = 100;  ///< M: the filter has 2M + 1 taps. Must be ≥ 2.
  double band = 0.2;      ///< Ωg: band edge, rad/sample, in [kMinBand, π].
  double dt = 0.001;      ///< Δ: sample period, s.

  /// Throws InputError (fields "half_length", "band", "dt") unless the settings are usable.
  void validate() const;
  bool operator==(const FilterSettings&) const = default;
};

/// Coefficients of the three filters for one (M, Ωg, Δ); immutable once built.
class DifferentialFilter {
 public:
  explicit DifferentialFilter(const FilterSettings& settings);

  const FilterSettings& settings() const { return settings_; }
  /// Taps c[n], n = −M..M stored at index n + M; output y[i] = Σ_n c[n] x[i + n].
  const Eigen::VectorXd& coefficients(FilterOrder order) const;

  /// Number of outputs for `input_samples` inputs: N − 2M − 1 (≤ 0 means too few samples).
  int output_length(int input_samples) const { return output_length(input_samples, settings_.half_length); }
  /// The same for any filter of half-length M.
  static int output_length(int input_samples, int half_length) { return input_samples - 2 * half_length - 1; }
  /// The fewest inputs that give an output: 2M + 2 (the one rule every layer counts samples by).
  static constexpr int min_input_samples(int half_length) { return 2 * half_length + 2; }
  /// output_length(input_samples), or InputError("samples") saying how many samples the filter
  /// needs when that is below one.
  int checked_output_length(int input_samples) const;
  /// Index of the input sample that output j is centred on (0-based): M + j.
  int first_output_index() const { return settings_.half_length; }

  /// Filters x into y (y must have output_length(x.size()) entries). Throws InputError
  /// ("samples") when x is too short. Long filters (M ≥ fft_min_half_length) on enough data go
  /// through the FFT (overlap-save, FFTW's transforms, see uses_fft): the same outputs up to
  /// rounding, at a cost that hardly grows with M where the direct sum's grows as M. (A NaN or
  /// infinity in x then spoils its whole block of outputs, not only the windows that hold it;
  /// trajectories are checked finite before they are filtered.)
  void apply(FilterOrder order, const Eigen::Ref<const Eigen::VectorXd>& x,
             Eigen::Ref<Eigen::VectorXd> y) const;
  Eigen::VectorXd apply(FilterOrder order, const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// The direct sum whatever M: where x is exactly zero over a whole window the output is
  /// exactly zero, which the FFT's rounding does not keep (a step's flat start stays at rest).
  void apply_direct(FilterOrder order, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const;
  /// All three orders in one pass over x (the identification's common case).
  void apply_all(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> lowpass,
                 Eigen::Ref<Eigen::VectorXd> derivative1, Eigen::Ref<Eigen::VectorXd> derivative2) const;

  /// H(Ω) = Σ_n c[n] e^{iΩn}, Ω in rad/sample (the response to e^{iΩt/Δ}, in physical units).
  std::complex<double> frequency_response(FilterOrder order, double omega) const;

  /// Whether apply() and apply_all() on `input_samples` samples go through the FFT: M at least
  /// fft_min_half_length and at most fft_max_half_length, and at least a transform block's worth
  /// of outputs.
  bool uses_fft(int input_samples) const;

  /// Half-lengths from which apply() and apply_all() may use the FFT (see filters.cpp). Per
  /// call the FFT is the faster from M ≈ 40 on all three orders (~0.3 ms for 4 × 9,701 samples
  /// whatever M, against 0.65 ms direct at M = 100), but a process pays once for FFTW's first
  /// plan (~1 ms with loading the library): from M = 64, `manipid identify` with the paper's M = 100 took
  /// as long as with the direct sum (medians of 40, 2026-11-27), so a one-shot command gains
  /// nothing below M = 192, and a service loses little.
  static constexpr int fft_min_half_length = 192;
  static constexpr int fft_max_half_length = 16384;

 private:
  struct Spectra;
  const Spectra& spectra() const;
  void apply(FilterOrder order, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y,
             bool fft_allowed) const;

  FilterSettings settings_;
  Eigen::VectorXd lowpass_, derivative1_, derivative2_;
  // The taps' transforms for the FFT path, made on first use (long filters only).
  mutable std::shared_ptr<const Spectra> spectra_;
  mutable std::once_flag spectra_once_;
};

/// A shared filter for these settings, built once and reused (thread-safe cache).
std::shared_ptr<const DifferentialFilter> cached_filter(const FilterSettings& settings);

}  // namespace manipid

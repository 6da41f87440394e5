// filters_test.cpp — the paper's differential filters (filters.h): coefficients against the
// paper's formulas, exactness on polynomials, accuracy on sinusoids, output alignment,
// measured frequency response, input validation, the cache, and apply_all.
#include "manipid/core/signal/filters.h"

#include "manipid/core/errors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <thread>
#include <vector>

namespace manipid {
namespace {

constexpr double pi = std::numbers::pi;
constexpr FilterOrder all_orders[] = {FilterOrder::lowpass, FilterOrder::derivative1, FilterOrder::derivative2};

FilterSettings make_settings(int half_length, double band, double dt) {
  FilterSettings settings;
  settings.half_length = half_length;
  settings.band = band;
  settings.dt = dt;
  return settings;
}

const FilterSettings paper = make_settings(100, 0.2, 0.001);
// Paper's settings first, then short/wide, long/narrow and odd tap counts (remainder loops).
const std::vector<FilterSettings> various = {paper, make_settings(40, 1.0, 0.002), make_settings(250, 0.05, 0.01),
                                             make_settings(7, 2.0, 0.5), make_settings(2, 0.3, 0.001),
                                             make_settings(101, 0.15, 0.001)};

// x[i] = f(t0 + i·dt), i = 0..count−1.
Eigen::VectorXd sampled(Eigen::Index count, double t0, double dt, const std::function<double(double)>& f) {
  Eigen::VectorXd x(count);
  for (Eigen::Index i = 0; i < count; ++i) x[i] = f(t0 + static_cast<double>(i) * dt);
  return x;
}

// Largest |y[j] − expected(t_j)| over all outputs, t_j the time of the input output j is
// centred on (M + j).
double max_error(const Eigen::VectorXd& y, double t0, const FilterSettings& settings,
                 const std::function<double(double)>& expected) {
  double worst = 0.0;
  for (Eigen::Index j = 0; j < y.size(); ++j) {
    const double t = t0 + static_cast<double>(settings.half_length + j) * settings.dt;
    worst = std::max(worst, std::abs(y[j] - expected(t)));
  }
  return worst;
}

// The paper's Filtr/Filtr1/Filtr2 taps, computed literally (closed forms, then its
// normalisations) in long double: an independent reference for the coefficients.
std::vector<Eigen::VectorXd> paper_coefficients(const FilterSettings& settings) {
  using Real = long double;
  const int m = settings.half_length;
  const Real band = settings.band, dt = settings.dt, lpi = std::numbers::pi_v<long double>;
  std::vector<Real> h0w(2 * m + 1), h1w(2 * m + 1), h2w(2 * m + 1);
  for (int n = -m; n <= m; ++n) {
    const Real rn = n, x = band * rn;
    const Real window = 0.36L + 0.49L * std::cos(rn * lpi / m) + 0.14L * std::cos(2 * rn * lpi / m) +
                        0.01L * std::cos(3 * rn * lpi / m);
    Real h0 = band / lpi, h1 = 0, h2 = -band * band * band / (3 * lpi * dt * dt);
    if (n != 0) {
      h0 = std::sin(x) / (lpi * rn);
      h1 = (band * std::cos(x) / rn - std::sin(x) / (rn * rn)) / (lpi * dt);
      h2 = -(band * band * std::sin(x) / rn + 2 * band * std::cos(x) / (rn * rn) - 2 * std::sin(x) / (rn * rn * rn)) /
           (lpi * dt * dt);
    }
    h0w[n + m] = h0 * window;
    h1w[n + m] = h1 * window;
    h2w[n + m] = h2 * window;
  }
  Real xh1 = 0, xh2 = 0, xh3 = 0, xh4 = 0;
  for (int n = -m; n <= m; ++n) {
    xh1 += h0w[n + m];
    xh2 += h1w[n + m] * (0 - n * dt);
    xh3 += h2w[n + m];
  }
  for (int n = -m; n <= m; ++n) xh4 += (h2w[n + m] - xh3 * h0w[n + m] / xh1) * (0 - (dt * n) * (dt * n));
  std::vector<Eigen::VectorXd> taps(3, Eigen::VectorXd(2 * m + 1));
  for (int n = -m; n <= m; ++n) {
    taps[0][n + m] = static_cast<double>(h0w[n + m] / xh1);
    taps[1][n + m] = static_cast<double>(h1w[n + m] * (-1 / xh2));
    taps[2][n + m] = static_cast<double>(-2 / xh4 * (h2w[n + m] - xh3 * h0w[n + m] / xh1));
  }
  return taps;
}

TEST(Filters, CoefficientsMatchThePapersFormulas) {
  for (const auto& settings : {paper, make_settings(100, 0.025, 0.001), make_settings(10, 0.5, 0.01),
                               make_settings(40, 1.0, 0.002), make_settings(2, pi, 1.0)}) {
    const DifferentialFilter filter(settings);
    const auto reference = paper_coefficients(settings);
    for (int order = 0; order < 3; ++order) {
      const Eigen::VectorXd& taps = filter.coefficients(all_orders[order]);
      ASSERT_EQ(taps.size(), 2 * settings.half_length + 1);
      const double scale = reference[order].cwiseAbs().maxCoeff();
      EXPECT_LE((taps - reference[order]).cwiseAbs().maxCoeff(), 1e-12 * scale)
          << "order " << order << ", M = " << settings.half_length << ", band = " << settings.band;
    }
  }
}

TEST(Filters, CoefficientsHaveThePapersNormalisationAndSymmetry) {
  for (const auto& settings : various) {
    const DifferentialFilter filter(settings);
    const int m = settings.half_length;
    const Eigen::VectorXd& c0 = filter.coefficients(FilterOrder::lowpass);
    const Eigen::VectorXd& c1 = filter.coefficients(FilterOrder::derivative1);
    const Eigen::VectorXd& c2 = filter.coefficients(FilterOrder::derivative2);
    double dc0 = 0, ramp1 = 0, dc2 = 0, parabola2 = 0;
    for (int n = -m; n <= m; ++n) {
      EXPECT_EQ(c0[m + n], c0[m - n]);
      EXPECT_EQ(c1[m + n], -c1[m - n]);
      EXPECT_EQ(c2[m + n], c2[m - n]);
      dc0 += c0[m + n];
      ramp1 += c1[m + n] * n * settings.dt;
      dc2 += c2[m + n];
      parabola2 += c2[m + n] * (n * settings.dt) * (n * settings.dt);
    }
    EXPECT_NEAR(dc0, 1.0, 1e-14);
    EXPECT_NEAR(ramp1, 1.0, 1e-14);
    EXPECT_NEAR(parabola2, 2.0, 1e-13);
    EXPECT_LE(std::abs(dc2), 1e-14 * c2.cwiseAbs().sum());
    // The window vanishes at n = ±M.
    EXPECT_LE(std::abs(c0[0]), 1e-15 * c0.cwiseAbs().maxCoeff());
  }
}

// When Ωg·M → 0 the paper's h2·w − xH3·h0FH cancels to ~(Ωg·M)²; the implementation must
// still give the limit c2 ∝ w(n)·(n² − μ), μ = Σ w n² / Σ w (and c0 ∝ w, c1 ∝ n w).
TEST(Filters, TinyBandTimesLengthKeepsFullPrecision) {
  const FilterSettings settings = make_settings(5, 1e-7, 0.01);
  const DifferentialFilter filter(settings);
  const int m = settings.half_length;
  Eigen::VectorXd window(2 * m + 1), n2(2 * m + 1), n1(2 * m + 1);
  for (int n = -m; n <= m; ++n) {
    const double phase = pi * n / m;
    window[n + m] = 0.36 + 0.49 * std::cos(phase) + 0.14 * std::cos(2 * phase) + 0.01 * std::cos(3 * phase);
    n1[n + m] = n * settings.dt;
    n2[n + m] = n1[n + m] * n1[n + m];
  }
  const Eigen::VectorXd c0 = window / window.sum();
  const Eigen::VectorXd c1 = window.cwiseProduct(n1) / window.cwiseProduct(n1).cwiseProduct(n1).sum();
  const double mu = window.cwiseProduct(n2).sum() / window.sum();
  const Eigen::VectorXd g = window.cwiseProduct(n2 - Eigen::VectorXd::Constant(2 * m + 1, mu));
  const Eigen::VectorXd c2 = 2.0 * g / g.cwiseProduct(n2).sum();
  // Corrections are O((Ωg·M)²) = 2.5e-13.
  EXPECT_LE((filter.coefficients(FilterOrder::lowpass) - c0).cwiseAbs().maxCoeff(), 1e-11 * c0.cwiseAbs().maxCoeff());
  EXPECT_LE((filter.coefficients(FilterOrder::derivative1) - c1).cwiseAbs().maxCoeff(),
            1e-11 * c1.cwiseAbs().maxCoeff());
  EXPECT_LE((filter.coefficients(FilterOrder::derivative2) - c2).cwiseAbs().maxCoeff(),
            1e-11 * c2.cwiseAbs().maxCoeff());
}

TEST(Filters, LowpassReproducesConstantsAndRamps) {
  for (const auto& settings : various) {
    const DifferentialFilter filter(settings);
    const Eigen::Index count = 2 * settings.half_length + 1 + 777;
    const double t0 = -0.3 * static_cast<double>(count) * settings.dt;
    for (const auto& [offset, slope] : {std::pair{3.5, 0.0}, std::pair{-1.25, 2.0}, std::pair{0.5, -40.0}}) {
      auto line = [&](double t) { return offset + slope * t; };
      const Eigen::VectorXd x = sampled(count, t0, settings.dt, line);
      const Eigen::VectorXd y = filter.apply(FilterOrder::lowpass, x);
      ASSERT_EQ(y.size(), 777);
      EXPECT_LE(max_error(y, t0, settings, line), 1e-9 * x.cwiseAbs().maxCoeff())
          << "M = " << settings.half_length << ", slope " << slope;
    }
  }
}

TEST(Filters, Derivative1GivesTheSlopeOfRampsAndTheTangentOfParabolas) {
  for (const auto& settings : various) {
    const DifferentialFilter filter(settings);
    const Eigen::Index count = 2 * settings.half_length + 1 + 600;
    const double t0 = -0.4 * static_cast<double>(count) * settings.dt;
    const Eigen::VectorXd ramp = sampled(count, t0, settings.dt, [](double t) { return 0.7 - 3.0 * t; });
    EXPECT_LE(max_error(filter.apply(FilterOrder::derivative1, ramp), t0, settings, [](double) { return -3.0; }),
              1e-9 * 3.0);
    // An antisymmetric filter sees no even moment: a·t² + b·t + c gives 2a·t + b exactly.
    auto parabola = [](double t) { return 2.5 * t * t + 0.5 * t - 1.0; };
    auto tangent = [](double t) { return 5.0 * t + 0.5; };
    const Eigen::VectorXd x = sampled(count, t0, settings.dt, parabola);
    const double scale = 5.0 * (std::abs(t0) + static_cast<double>(count) * settings.dt) + 0.5;
    EXPECT_LE(max_error(filter.apply(FilterOrder::derivative1, x), t0, settings, tangent), 1e-9 * scale)
        << "M = " << settings.half_length;
  }
}

TEST(Filters, Derivative2GivesTwiceTheLeadingCoefficientOfParabolas) {
  for (const auto& settings : various) {
    const DifferentialFilter filter(settings);
    const Eigen::Index count = 2 * settings.half_length + 1 + 500;
    const double t0 = -0.5 * static_cast<double>(count) * settings.dt;
    for (const double a : {1.0, -3.0, 0.01}) {
      auto parabola = [a](double t) { return a * t * t - 2.0 * t + 0.25; };
      const Eigen::VectorXd x = sampled(count, t0, settings.dt, parabola);
      const Eigen::VectorXd y = filter.apply(FilterOrder::derivative2, x);
      // 1e-9 relative, unless rounding (~ε·Σ|c2|·max|x|) is larger: a flat parabola next to
      // a steep line under a short filter.
      const double rounding = 1e-13 * filter.coefficients(FilterOrder::derivative2).cwiseAbs().sum() *
                              x.cwiseAbs().maxCoeff();
      EXPECT_LE(max_error(y, t0, settings, [a](double) { return 2 * a; }), std::max(1e-9 * std::abs(2 * a), rounding))
          << "M = " << settings.half_length << ", a = " << a;
    }
    // Its DC and ramp responses are zero.
    const Eigen::VectorXd line = sampled(count, t0, settings.dt, [](double t) { return 4.0 - 7.0 * t; });
    EXPECT_LE(filter.apply(FilterOrder::derivative2, line).cwiseAbs().maxCoeff(),
              1e-12 * filter.coefficients(FilterOrder::derivative2).cwiseAbs().sum() * line.cwiseAbs().maxCoeff());
  }
}

// The paper's scale: 10 s at 1 kHz, t² up to 100.
TEST(Filters, PolynomialsOverTheWholePaperRecord) {
  const DifferentialFilter filter(paper);
  const Eigen::VectorXd x = sampled(10001, 0.0, paper.dt, [](double t) { return t * t; });
  Eigen::VectorXd y0(filter.output_length(10001)), y1(y0.size()), y2(y0.size());
  filter.apply_all(x, y0, y1, y2);
  EXPECT_LE(max_error(y1, 0.0, paper, [](double t) { return 2 * t; }), 1e-9 * 20.0);
  EXPECT_LE(max_error(y2, 0.0, paper, [](double) { return 2.0; }), 1e-9 * 2.0);
}

// ω = 20 rad/s with Δ = 1 ms is Ω = 0.02 rad/sample = Ωg/10. Bounds are relative to the
// amplitude ω^k of the k-th derivative. The paper's window leaves a passband ripple that the
// derivatives amplify: at this Ω the frequency response predicts 1.1e-6 (value), 4.1e-5
// (first) and 3.1e-4 (second derivative); the second derivative is within 1e-4 only below
// Ω ≈ 0.0105 (it grows ∝ Ω² from 0), so it gets its own bound.
TEST(Filters, SinusoidWellInsideTheBand) {
  const double omega = 20.0;
  const DifferentialFilter filter(paper);
  const double t0 = 0.123;
  const Eigen::VectorXd x = sampled(3000, t0, paper.dt, [omega](double t) { return std::sin(omega * t); });
  EXPECT_LE(max_error(filter.apply(FilterOrder::lowpass, x), t0, paper,
                      [omega](double t) { return std::sin(omega * t); }),
            1e-5);
  EXPECT_LE(max_error(filter.apply(FilterOrder::derivative1, x), t0, paper,
                      [omega](double t) { return omega * std::cos(omega * t); }) / omega,
            1e-4);
  EXPECT_LE(max_error(filter.apply(FilterOrder::derivative2, x), t0, paper,
                      [omega](double t) { return -omega * omega * std::sin(omega * t); }) / (omega * omega),
            5e-4);

  // Lower in the band all three are within 1e-4.
  const double slow = 5.0;  // 0.005 rad/sample
  const Eigen::VectorXd xs = sampled(3000, t0, paper.dt, [slow](double t) { return std::cos(slow * t); });
  EXPECT_LE(max_error(filter.apply(FilterOrder::derivative2, xs), t0, paper,
                      [slow](double t) { return -slow * slow * std::cos(slow * t); }) / (slow * slow),
            1e-4);
}

// apply() on e^{iΩn} must equal H(Ω)·e^{iΩn} — in the passband, transition and stopband.
TEST(Filters, ApplyAgreesWithFrequencyResponse) {
  const DifferentialFilter filter(paper);
  for (const double omega : {0.02, 0.2, 0.25, 1.3}) {
    const Eigen::VectorXd c = sampled(800, 0.0, 1.0, [omega](double n) { return std::cos(omega * n); });
    const Eigen::VectorXd s = sampled(800, 0.0, 1.0, [omega](double n) { return std::sin(omega * n); });
    for (const FilterOrder order : all_orders) {
      const std::complex<double> h = filter.frequency_response(order, omega);
      const Eigen::VectorXd yc = filter.apply(order, c), ys = filter.apply(order, s);
      const double tolerance = 1e-12 * filter.coefficients(order).cwiseAbs().sum();
      for (Eigen::Index j = 0; j < yc.size(); ++j) {
        const std::complex<double> expected = h * std::polar(1.0, omega * static_cast<double>(paper.half_length + j));
        ASSERT_NEAR(yc[j], expected.real(), tolerance) << "Ω = " << omega << ", order " << static_cast<int>(order);
        ASSERT_NEAR(ys[j], expected.imag(), tolerance) << "Ω = " << omega << ", order " << static_cast<int>(order);
      }
    }
  }
}

TEST(Filters, OutputJIsCentredOnInputMPlusJ) {
  for (const auto& settings : {paper, make_settings(3, 0.5, 0.1)}) {
    const DifferentialFilter filter(settings);
    const int m = settings.half_length;
    const int count = 2 * m + 1 + 20;
    EXPECT_EQ(filter.output_length(count), 20);
    EXPECT_EQ(filter.first_output_index(), m);
    // A ramp in sample units returns its own index through the low-pass.
    Eigen::VectorXd index(count);
    for (int i = 0; i < count; ++i) index[i] = i;
    const Eigen::VectorXd y = filter.apply(FilterOrder::lowpass, index);
    ASSERT_EQ(y.size(), 20);
    for (int j = 0; j < 20; ++j) EXPECT_NEAR(y[j], m + j, 1e-9 * count);
    // A unit impulse at input k: y[j] = Σ_n c[n] x[M + j + n] = c[k − M − j] (correlation,
    // not convolution: the derivative's sign depends on it).
    const int k = m + 10;
    Eigen::VectorXd impulse = Eigen::VectorXd::Zero(count);
    impulse[k] = 1.0;
    for (const FilterOrder order : all_orders) {
      const Eigen::VectorXd response = filter.apply(order, impulse);
      const Eigen::VectorXd& taps = filter.coefficients(order);
      for (int j = 0; j < 20; ++j) {
        const int n = k - m - j;
        EXPECT_EQ(response[j], std::abs(n) <= m ? taps[n + m] : 0.0) << "j = " << j;
      }
    }
    // A rising step gives a positive first derivative.
    const Eigen::VectorXd step = sampled(count, 0.0, 1.0, [m](double i) { return i >= m + 10 ? 1.0 : 0.0; });
    EXPECT_GT(filter.apply(FilterOrder::derivative1, step)[10], 0.0);
  }
}

// Passband/stopband limits follow the measured transition: |H0| falls from 1 − 1e-4 to 1e-4
// over Ωg ± 10.7/M rad/sample (half amplitude at Ωg), and stays below ~1.5e-6 (the window's
// sidelobe floor) beyond Ωg + 20/M. Derivative bounds are relative to the ideal iΩ/Δ,
// −(Ω/Δ)² in the passband and to Ωg/Δ, (Ωg/Δ)² in the stopband.
TEST(Filters, FrequencyResponseMatchesTheIdealOutsideTheTransition) {
  for (const auto& settings : {paper, make_settings(40, 1.0, 0.002)}) {
    const DifferentialFilter filter(settings);
    const double band = settings.band, dt = settings.dt, margin = 11.0 / settings.half_length;
    double pass0 = 0, pass1 = 0, pass2 = 0, stop0 = 0, stop1 = 0, stop2 = 0, floor0 = 0;
    for (double omega = 1e-4; omega <= pi; omega += 1e-4) {
      const auto h0 = filter.frequency_response(FilterOrder::lowpass, omega);
      const auto h1 = filter.frequency_response(FilterOrder::derivative1, omega);
      const auto h2 = filter.frequency_response(FilterOrder::derivative2, omega);
      ASSERT_EQ(h0.imag(), 0.0);
      ASSERT_EQ(h1.real(), 0.0);
      ASSERT_EQ(h2.imag(), 0.0);
      if (omega <= band - margin) {
        pass0 = std::max(pass0, std::abs(h0.real() - 1.0));
        pass1 = std::max(pass1, std::abs(h1.imag() * dt / omega - 1.0));
        pass2 = std::max(pass2, std::abs(-h2.real() * dt * dt / (omega * omega) - 1.0));
      } else if (omega >= band + margin) {
        stop0 = std::max(stop0, std::abs(h0.real()));
        stop1 = std::max(stop1, std::abs(h1.imag()) * dt / band);
        stop2 = std::max(stop2, std::abs(h2.real()) * dt * dt / (band * band));
        if (omega >= band + 20.0 / settings.half_length) floor0 = std::max(floor0, std::abs(h0.real()));
      }
    }
    EXPECT_LE(pass0, 1e-4);  // measured 4.9e-5 / 5.0e-5
    EXPECT_LE(pass1, 2e-4);  // measured 1.0e-4 / 1.1e-4
    EXPECT_LE(pass2, 1.5e-3);  // measured 5.8e-4 / 9.2e-4
    EXPECT_LE(stop0, 1e-4);  // measured 5.1e-5
    EXPECT_LE(stop1, 1e-4);
    EXPECT_LE(stop2, 1e-4);
    EXPECT_LE(floor0, 3e-6);  // measured 1.3e-6
    EXPECT_NEAR(filter.frequency_response(FilterOrder::lowpass, band).real(), 0.5, 1e-4);
    EXPECT_DOUBLE_EQ(filter.frequency_response(FilterOrder::lowpass, 0.0).real(), 1.0);
  }
}

TEST(Filters, InvalidSettingsNameTheirField) {
  auto field_of = [](const FilterSettings& settings) -> std::string {
    try {
      settings.validate();
    } catch (const InputError& error) {
      EXPECT_THROW(DifferentialFilter{settings}, InputError);
      EXPECT_THROW(cached_filter(settings), InputError);
      return error.field();
    }
    return "";
  };
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (const int m : {1, 0, -3, 2'000'000}) EXPECT_EQ(field_of(make_settings(m, 0.2, 0.001)), "half_length") << m;
  for (const double band : {0.0, -0.1, 3.2, nan, inf}) EXPECT_EQ(field_of(make_settings(100, band, 0.001)), "band");
  for (const double dt : {0.0, -0.001, nan, inf}) EXPECT_EQ(field_of(make_settings(100, 0.2, dt)), "dt");
  EXPECT_EQ(field_of(make_settings(2, pi, 1e-9)), "");
  EXPECT_EQ(field_of(paper), "");
}

TEST(Filters, TooShortInputIsRejected) {
  const DifferentialFilter filter(paper);
  for (const FilterOrder order : all_orders) {
    try {
      filter.apply(order, Eigen::VectorXd::Zero(201));
      ADD_FAILURE() << "201 samples accepted";
    } catch (const InputError& error) {
      EXPECT_EQ(error.field(), "samples");
      EXPECT_NE(std::string(error.what()).find("202"), std::string::npos) << error.what();
    }
  }
  Eigen::VectorXd y0(1), y1(1), y2(1);
  EXPECT_THROW(filter.apply_all(Eigen::VectorXd::Zero(10), y0, y1, y2), InputError);
  // 2M + 2 samples give exactly one output.
  EXPECT_EQ(filter.apply(FilterOrder::lowpass, Eigen::VectorXd::Ones(202)).size(), 1);
  filter.apply_all(Eigen::VectorXd::Ones(202), y0, y1, y2);
  EXPECT_NEAR(y0[0], 1.0, 1e-14);
  // A wrongly sized output is a caller error.
  Eigen::VectorXd wrong(5);
  EXPECT_THROW(filter.apply(FilterOrder::lowpass, Eigen::VectorXd::Ones(300), wrong), std::invalid_argument);
  EXPECT_THROW(filter.apply_all(Eigen::VectorXd::Ones(202), y0, wrong, y2), std::invalid_argument);
}

TEST(Filters, CachedFilterSharesOneObjectPerSettings) {
  const auto first = cached_filter(paper);
  EXPECT_EQ(cached_filter(paper), first);
  EXPECT_EQ(first->settings(), paper);
  EXPECT_NE(cached_filter(make_settings(100, 0.2, 0.002)), first);
  EXPECT_NE(cached_filter(make_settings(100, 0.25, 0.001)), first);
  EXPECT_NE(cached_filter(make_settings(99, 0.2, 0.001)), first);

  // Concurrent first requests for new settings still end up sharing one filter.
  const FilterSettings fresh = make_settings(123, 0.321, 0.004);
  std::vector<std::shared_ptr<const DifferentialFilter>> seen(8);
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < seen.size(); ++i) threads.emplace_back([&, i] { seen[i] = cached_filter(fresh); });
  for (auto& thread : threads) thread.join();
  for (const auto& filter : seen) EXPECT_EQ(filter, seen.front());
  EXPECT_EQ(cached_filter(fresh), seen.front());
}

TEST(Filters, ApplyAllEqualsTheThreeSingleApplies) {
  for (const auto& settings : various) {
    const DifferentialFilter filter(settings);
    // Long enough to cross output blocks; irregular so that any misplaced tap shows.
    const Eigen::VectorXd x = sampled(2 * settings.half_length + 1 + 1500, 0.0, 1.0, [](double i) {
      return std::sin(0.01 * i) + 0.3 * std::cos(0.37 * i * i) + 1e-3 * i;
    });
    const Eigen::Index outputs = filter.output_length(static_cast<int>(x.size()));
    Eigen::VectorXd y0(outputs), y1(outputs), y2(outputs);
    filter.apply_all(x, y0, y1, y2);
    const Eigen::VectorXd* all[] = {&y0, &y1, &y2};
    for (int order = 0; order < 3; ++order) {
      const Eigen::VectorXd single = filter.apply(all_orders[order], x);
      const double tolerance = 1e-13 * filter.coefficients(all_orders[order]).cwiseAbs().sum() * x.cwiseAbs().maxCoeff();
      EXPECT_LE((single - *all[order]).cwiseAbs().maxCoeff(), tolerance) << "order " << order;
    }
  }
}

// Long filters on long records go through the FFT (filters.h); short records of the same
// filters through the direct sum. Both against a long-double sum of the taps, each output.
TEST(Filters, LongFiltersThroughTheFftAgreeWithTheDirectSum) {
  for (const FilterSettings& settings : {make_settings(DifferentialFilter::fft_min_half_length, 0.3, 0.001),
                                         make_settings(400, 2.4, 0.001), make_settings(1000, 0.1, 0.002)}) {
    const DifferentialFilter filter(settings);
    const int m = settings.half_length;
    // 16,391 outputs: more than a block's (B is 4,096 up to M = 511, 8,192 up to M = 1,023),
    // the last block partial; and 2M outputs, fewer than a block, for the direct sum.
    for (const int outputs : {2 * 8192 + 7, 2 * m}) {
      EXPECT_EQ(filter.uses_fft(2 * m + 1 + outputs), outputs > 2 * m) << "M " << m << ": FFTW (libfftw3-double3) loads";
      const Eigen::VectorXd x = sampled(2 * m + 1 + outputs, 0.0, 1.0, [](double i) {
        return std::sin(0.01 * i) + 0.3 * std::cos(0.37 * i * i) + 1e-3 * i;
      });
      Eigen::VectorXd all[3] = {Eigen::VectorXd(outputs), Eigen::VectorXd(outputs), Eigen::VectorXd(outputs)};
      filter.apply_all(x, all[0], all[1], all[2]);
      for (int order = 0; order < 3; ++order) {
        const Eigen::VectorXd& taps = filter.coefficients(all_orders[order]);
        const Eigen::VectorXd single = filter.apply(all_orders[order], x);
        const double scale = taps.cwiseAbs().sum() * x.cwiseAbs().maxCoeff();
        double worst_all = 0.0, worst_single = 0.0;
        for (int j = 0; j < outputs; ++j) {
          long double sum = 0.0L;
          for (int n = 0; n <= 2 * m; ++n) sum += static_cast<long double>(taps[n]) * x[j + n];
          worst_all = std::max(worst_all, std::abs(all[order][j] - static_cast<double>(sum)));
          worst_single = std::max(worst_single, std::abs(single[j] - static_cast<double>(sum)));
        }
        EXPECT_LE(worst_all, 1e-14 * scale) << "M " << m << ", order " << order << ", " << outputs << " outputs";
        EXPECT_LE(worst_single, 1e-14 * scale) << "M " << m << ", order " << order << ", " << outputs << " outputs";
      }
    }
  }
}

// apply_direct takes the direct sum even where apply would take the FFT: a step's flat start
// stays exactly zero (the simulated reference starts at rest), and the two agree to rounding.
TEST(Filters, ApplyDirectKeepsAStepsFlatStartExactlyZero) {
  const DifferentialFilter filter(make_settings(200, 0.2, 0.001));
  Eigen::VectorXd step = Eigen::VectorXd::Zero(9'901);
  step.tail(5'000).setConstant(0.5);
  ASSERT_TRUE(filter.uses_fft(static_cast<int>(step.size())));
  Eigen::VectorXd direct(filter.output_length(static_cast<int>(step.size())));
  filter.apply_direct(FilterOrder::lowpass, step, direct);
  const Eigen::VectorXd by_fft = filter.apply(FilterOrder::lowpass, step);
  // Outputs 0 … 4,500 see only the zeros (window 2M + 1 = 401 samples from the output's index).
  EXPECT_EQ(direct.head(4'501).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_NEAR(direct[direct.size() - 1], 0.5, 1e-3);  // the plateau, to the filter's DC gain
  EXPECT_LE((direct - by_fft).cwiseAbs().maxCoeff(), 1e-14 * filter.coefficients(FilterOrder::lowpass).cwiseAbs().sum() * 0.5);
}

// The FFT path's transforms are made once per filter, whichever thread comes first.
TEST(Filters, ThreadsShareALongFiltersTransforms) {
  const DifferentialFilter filter(make_settings(400, 0.2, 0.001));
  const Eigen::VectorXd x = sampled(20'000, 0.0, 0.001, [](double t) { return std::sin(3 * t) + 0.1 * t * t; });
  std::vector<Eigen::VectorXd> results(4);
  std::vector<std::thread> threads;
  for (auto& result : results) {
    threads.emplace_back([&filter, &x, &result] { result = filter.apply(FilterOrder::derivative2, x); });
  }
  for (auto& thread : threads) thread.join();
  for (const auto& result : results) EXPECT_EQ(result, results.front());
  // q̈ of sin(3t) + 0.1 t² is −9 sin(3t) + 0.2, well inside the band (to the filter's passband ripple).
  EXPECT_NEAR(results.front()[5'000], -9 * std::sin(3 * 5.4) + 0.2, 1e-4);
}

TEST(Filters, OutputMayOverwriteItsOwnInput) {
  const DifferentialFilter filter(make_settings(20, 0.4, 0.01));
  const Eigen::VectorXd x = sampled(500, 0.0, 0.01, [](double t) { return std::exp(-t) * std::sin(3 * t); });
  for (const FilterOrder order : all_orders) {
    const Eigen::VectorXd expected = filter.apply(order, x);
    Eigen::VectorXd buffer = x;
    filter.apply(order, buffer, buffer.head(expected.size()));
    EXPECT_EQ(buffer.head(expected.size()), expected);
    buffer = x;
    filter.apply(order, buffer, buffer.tail(expected.size()));
    EXPECT_EQ(buffer.tail(expected.size()), expected);
  }
}

}  // namespace
}  // namespace manipid

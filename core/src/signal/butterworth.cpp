// butterworth.cpp — Butterworth design by the bilinear transform and zero-phase filtering (signal/butterworth.h).
#include "manipid/core/signal/butterworth.h"

#include "manipid/core/errors.h"
#include "numbers.h"

#include <Eigen/LU>

#include <cmath>
#include <complex>
#include <numbers>
#include <string>

namespace manipid {
namespace {

using Complex = std::complex<double>;

/// Coefficients of Π (x − root_k), highest power first (numpy.poly), real part.
std::vector<double> polynomial(const std::vector<Complex>& roots) {
  std::vector<Complex> c{1.0};
  for (const Complex& root : roots) {
    c.push_back(0.0);
    for (std::size_t i = c.size() - 1; i > 0; --i) c[i] -= root * c[i - 1];
  }
  std::vector<double> real(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) real[i] = c[i].real();
  return real;
}

/// The state that makes the filter's step response start at its steady state (scipy's lfilter_zi):
/// (I − Aᵀ) z = b[1:] − a[1:] b[0], A the companion matrix of a.
Eigen::VectorXd steady_state(const IirFilter& filter) {
  const int n = filter.order();
  Eigen::MatrixXd I_minus_At = Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd rhs(n);
  for (int i = 0; i < n; ++i) {
    I_minus_At(i, 0) += filter.a[static_cast<std::size_t>(i + 1)];  // companion's first row is −a[1:]
    if (i + 1 < n) I_minus_At(i, i + 1) -= 1.0;                       // its subdiagonal, transposed
    rhs[i] = filter.b[static_cast<std::size_t>(i + 1)] - filter.a[static_cast<std::size_t>(i + 1)] * filter.b[0];
  }
  return I_minus_At.partialPivLu().solve(rhs);
}

/// Direct form II transposed over `x` in place, from state `z` (consumed).
void run(const IirFilter& filter, Eigen::VectorXd& x, Eigen::VectorXd z) {
  const int n = filter.order();
  const double* b = filter.b.data();
  const double* a = filter.a.data();
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double input = x[i];
    const double output = b[0] * input + z[0];
    for (int k = 0; k + 1 < n; ++k) z[k] = b[k + 1] * input + z[k + 1] - a[k + 1] * output;
    z[n - 1] = b[n] * input - a[n] * output;
    x[i] = output;
  }
}

}  // namespace

IirFilter butterworth_lowpass(int order, double cutoff_hz, double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw InputError("dt", "the sample period must be a positive number of seconds");
  if (order < 1 || order > 8) throw InputError("order", "a Butterworth low-pass of order 1 to 8, not " + std::to_string(order));
  const double nyquist = 0.5 / dt;
  if (!(cutoff_hz > 0.0 && cutoff_hz < nyquist)) {
    throw InputError("cutoff_hz", "the low-pass cut-off must lie between 0 and the Nyquist frequency (" +
                                      detail::message_number(nyquist) + " Hz for samples " + detail::message_number(dt) + " s apart), not " +
                                      detail::message_number(cutoff_hz) + " Hz");
  }
  // Normalised as scipy does: sampling frequency 2, cut-off Wn = f_c / f_Nyquist.
  const double fs = 2.0;
  const double warped = 2.0 * fs * std::tan(std::numbers::pi * (cutoff_hz / nyquist) / fs);
  std::vector<Complex> poles;
  for (int k = -order + 1; k < order; k += 2) {
    poles.push_back(-std::exp(Complex(0.0, std::numbers::pi * k / (2.0 * order))) * warped);
  }
  double gain = std::pow(warped, order);
  const double fs2 = 2.0 * fs;
  Complex denominator = 1.0;
  for (Complex& pole : poles) {
    denominator *= fs2 - pole;
    pole = (fs2 + pole) / (fs2 - pole);
  }
  gain = (gain / denominator).real();
  const std::vector<Complex> zeros(static_cast<std::size_t>(order), Complex(-1.0, 0.0));
  IirFilter filter;
  filter.b = polynomial(zeros);
  for (double& c : filter.b) c *= gain;
  filter.a = polynomial(poles);
  return filter;
}

int filtfilt_padding(const IirFilter& filter) {
  return 3 * static_cast<int>(std::max(filter.a.size(), filter.b.size()));
}

void filtfilt(const IirFilter& filter, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) {
  const Eigen::Index N = x.size();
  const Eigen::Index pad = filtfilt_padding(filter);
  if (N <= pad) {
    throw InputError("samples", "a zero-phase low-pass needs more than " + std::to_string(pad) + " samples; the signal has " +
                                    std::to_string(N));
  }
  Eigen::VectorXd extended(N + 2 * pad);
  for (Eigen::Index i = 0; i < pad; ++i) {
    extended[i] = 2.0 * x[0] - x[pad - i];
    extended[N + pad + i] = 2.0 * x[N - 1] - x[N - 2 - i];
  }
  extended.segment(pad, N) = x;
  const Eigen::VectorXd zi = steady_state(filter);
  run(filter, extended, zi * extended[0]);
  extended.reverseInPlace();
  run(filter, extended, zi * extended[0]);
  extended.reverseInPlace();
  y = extended.segment(pad, N);
}

Eigen::MatrixXd filtfilt_columns(const IirFilter& filter, const Eigen::Ref<const Eigen::MatrixXd>& x) {
  // All columns at once, one sample (a row of a row-major copy) at a time: the same operations per column as
  // filtfilt(), in vector lanes across the columns.
  using Rows = Eigen::Array<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::Index N = x.rows(), C = x.cols();
  const Eigen::Index pad = filtfilt_padding(filter);
  if (C == 0) return Eigen::MatrixXd(N, 0);
  if (N <= pad) {
    throw InputError("samples", "a zero-phase low-pass needs more than " + std::to_string(pad) + " samples; the signal has " +
                                    std::to_string(N));
  }
  Rows extended(N + 2 * pad, C);
  extended.middleRows(pad, N) = x.array();
  for (Eigen::Index i = 0; i < pad; ++i) {
    extended.row(i) = 2.0 * x.row(0).array() - x.row(pad - i).array();
    extended.row(N + pad + i) = 2.0 * x.row(N - 1).array() - x.row(N - 2 - i).array();
  }
  const int n = filter.order();
  const Eigen::VectorXd zi = steady_state(filter);
  const double* b = filter.b.data();
  const double* a = filter.a.data();
  Rows z(n, C);
  Eigen::Array<double, 1, Eigen::Dynamic> input(C), output(C);
  const auto pass = [&](Eigen::Index first, Eigen::Index step) {
    for (int k = 0; k < n; ++k) z.row(k) = zi[k] * extended.row(first);
    for (Eigen::Index count = 0, i = first; count < extended.rows(); ++count, i += step) {
      input = extended.row(i);
      output = b[0] * input + z.row(0);
      for (int k = 0; k + 1 < n; ++k) z.row(k) = b[k + 1] * input + z.row(k + 1) - a[k + 1] * output;
      z.row(n - 1) = b[n] * input - a[n] * output;
      extended.row(i) = output;
    }
  };
  pass(0, 1);
  pass(extended.rows() - 1, -1);
  return extended.middleRows(pad, N).matrix();
}

}  // namespace manipid

// butterworth.h — the Butterworth low-pass and its zero-phase (forward-backward) application, as
// scipy.signal's butter() and filtfilt() define them, so figures computed here and by a lab's script agree.
//
// Design: the analogue prototype's poles −exp(iπ(2k − N + 1)/(2N)), k = 0..N−1, moved to the cut-off
// prewarped for the bilinear transform (ω = 2 f_s tan(π f_c / f_s)), mapped by z = (2f_s + s)/(2f_s − s),
// the N zeros at z = −1, and the gain that makes the response 1 at DC: b(z)/a(z) with a_0 = 1.
// Application (filtfilt): the signal extended at each end by 3·(N + 1) samples reflected about its end
// value ("odd" padding), filtered forward from the steady state of its first sample (lfilter_zi), then
// backward from the steady state of the last output, the extension dropped. Zero phase; the gain is
// |H|², −6 dB at the cut-off; a constant passes unchanged. Transients remain within about 1.5/f_c of each
// end: trim there (signal/judge.h does).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace manipid {

/// A digital IIR filter b(z)/a(z), a[0] = 1, applied in direct form II transposed.
struct IirFilter {
  std::vector<double> b, a;
  int order() const { return static_cast<int>(a.size()) - 1; }
};

/// The order-`order` Butterworth low-pass with its −3 dB point at `cutoff_hz` for samples `dt` apart.
/// Throws InputError("cutoff_hz") unless 0 < cutoff_hz < 1/(2 dt) (below Nyquist), InputError("dt") unless
/// dt > 0, InputError("order") unless 1 ≤ order ≤ 8.
IirFilter butterworth_lowpass(int order, double cutoff_hz, double dt);

/// How many samples filtfilt() adds at each end: 3·max(len a, len b).
int filtfilt_padding(const IirFilter& filter);

/// Zero-phase filtering of x into y (same length; x and y may be the same vector). Throws
/// InputError("samples") when x has no more than filtfilt_padding() samples.
void filtfilt(const IirFilter& filter, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y);

/// Every column of x (samples × signals), zero-phase.
Eigen::MatrixXd filtfilt_columns(const IirFilter& filter, const Eigen::Ref<const Eigen::MatrixXd>& x);

}  // namespace manipid

// numbers.h — the constants, the RMS and the number formatting core's files share (internal to core).
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace manipid::detail {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// `value` as a stream prints it by default (six significant digits): a value in a message.
inline std::string message_number(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

/// `value` with three significant digits: a figure in an explanation (a ratio, a bound).
inline std::string short_number(double value) {
  std::ostringstream text;
  text.precision(3);
  text << value;
  return text.str();
}

/// Root mean square over all entries of `x`; NaN for an empty array.
inline double rms(const Eigen::Ref<const Eigen::MatrixXd>& x) {
  return x.size() ? std::sqrt(x.squaredNorm() / static_cast<double>(x.size())) : kNaN;
}

}  // namespace manipid::detail

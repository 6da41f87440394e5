// history.h — one record of a minimiser's cost history: what every identification's evaluation log keeps.
#pragma once

#include <Eigen/Core>

namespace manipid::estimation {

struct HistoryRecord {
  long index = 0;         ///< the evaluation's number, counting across every stage of a run
  double cost = 0.0;
  Eigen::VectorXd theta;  ///< every parameter at that evaluation
};

}  // namespace manipid::estimation

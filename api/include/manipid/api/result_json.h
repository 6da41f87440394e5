// result_json.h — identification results as JSON: the object `manipid identify --json`
// prints and the service returns as a job's `result`.
//
// Shape (every parameter by name; numbers that do not exist — the standard error of a fixed
// or unidentifiable parameter — are null, never NaN):
//   { "method", "algorithm",
//     "estimates": {"m1": 50.2, ...}, "std_errors": {"m1": null, "m2": 0.0023, ...},
//     "initial": {...}, "free": ["m1", ...],
//     "correlation": {"parameters": [...], "matrix": [[...]]},
//     "identifiability": {"all_identifiable", "unidentifiable": [...],
//                         "combinations": [{"name", "value", "std_error"}], "findings": [...],
//                         "singular_values": [...]},
//     "initial_cost", "final_cost", "evaluations", "simulations", "refinement_steps",
//     "wall_seconds", "stop_reason", "cancelled",
//     "filter": {"half_length", "band", "dt", "automatic"}, "torque_source", "warnings": [...] }
#pragma once

#include "manipid/core/identification.h"

#include <nlohmann/json.hpp>

#include <vector>

namespace manipid::api {

nlohmann::ordered_json result_to_json(const IdentificationResult& result);
/// History records as {"index", "cost", "parameters": {"m1": ...}} objects.
nlohmann::ordered_json history_to_json(const std::vector<HistoryRecord>& history, const std::vector<std::string>& names);

}  // namespace manipid::api

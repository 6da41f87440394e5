// result_json.cpp — identification results to JSON (result_json.h).
#include "manipid/api/result_json.h"
#include "json_numbers.h"

#include <cmath>
#include <limits>

namespace manipid::api {
namespace {

using json_numbers::by_name;
using json_numbers::number;
using json_numbers::numbers;

const char* source_name(TorqueSource source) {
  switch (source) {
    case TorqueSource::reference: return "reference";
    case TorqueSource::measured: return "measured";
    default: return "automatic";
  }
}

nlohmann::ordered_json gains_to_json(const IdentificationResult& result) {
  nlohmann::ordered_json estimated = nullptr;
  if (result.estimated_gains) {
    estimated = {{"kp", numbers(result.estimated_gains->gains.kp)},
                 {"kd", numbers(result.estimated_gains->gains.kd)},
                 {"relative_residual", numbers(result.estimated_gains->relative_residual)}};
  }
  return {{"source", to_string(result.gain_source)},
          {"kp", result.controller ? numbers(result.controller->kp) : nlohmann::ordered_json(nullptr)},
          {"kd", result.controller ? numbers(result.controller->kd) : nlohmann::ordered_json(nullptr)},
          {"estimated", estimated}};
}

}  // namespace

nlohmann::ordered_json truth_to_json(const std::vector<std::string>& names, const Eigen::VectorXd& truth) {
  nlohmann::ordered_json object = nlohmann::ordered_json::object();
  for (std::size_t i = 0; i < names.size() && static_cast<Eigen::Index>(i) < truth.size(); ++i) {
    const double value = truth[static_cast<Eigen::Index>(i)];
    if (std::isfinite(value)) object[names[i]] = value;
  }
  return object.empty() ? nlohmann::ordered_json(nullptr) : object;
}

nlohmann::ordered_json result_to_json(const IdentificationResult& result, const Eigen::VectorXd& truth) {
  // What the data determine: a parameter they cannot separate from another (m1 and l1 of the
  // paper's robot) has no estimate of its own, only the combination in "identifiability".
  Eigen::VectorXd estimates = result.estimate;
  for (std::size_t i = 0; i < result.names.size(); ++i) {
    if (!result.identifiability.determines_alone(result.names[i])) {
      estimates[static_cast<Eigen::Index>(i)] = std::numeric_limits<double>::quiet_NaN();
    }
  }
  nlohmann::ordered_json free = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < result.names.size(); ++i) {
    if (result.free[i]) free.push_back(result.names[i]);
  }
  nlohmann::ordered_json matrix = nlohmann::ordered_json::array();
  for (Eigen::Index a = 0; a < result.correlation.rows(); ++a) {
    nlohmann::ordered_json row = nlohmann::ordered_json::array();
    for (Eigen::Index b = 0; b < result.correlation.cols(); ++b) row.push_back(number(result.correlation(a, b)));
    matrix.push_back(row);
  }
  const IdentifiabilityReport& report = result.identifiability;
  nlohmann::ordered_json combinations = nlohmann::ordered_json::array();
  for (const IdentifiableCombination& combination : report.combinations) {
    combinations.push_back(
        {{"name", combination.name}, {"value", number(combination.value)}, {"std_error", number(combination.std_error)}});
  }
  nlohmann::ordered_json singular = nlohmann::ordered_json::array();
  for (Eigen::Index i = 0; i < report.singular_values.size(); ++i) singular.push_back(number(report.singular_values[i]));

  return {
      {"method", to_string(result.method)},
      {"algorithm", result.algorithm},
      {"estimates", by_name(result.names, estimates)},
      {"point", by_name(result.names, result.estimate)},
      {"std_errors", by_name(result.names, result.std_errors)},
      {"initial", by_name(result.names, result.initial)},
      {"free", free},
      {"correlation", {{"parameters", free}, {"matrix", matrix}}},
      {"identifiability",
       {{"all_identifiable", report.all_identifiable()},
        {"unidentifiable", report.unidentifiable},
        {"combinations", combinations},
        {"findings", report.findings},
        {"singular_values", singular}}},
      {"initial_cost", number(result.initial_cost)},
      {"final_cost", number(result.final_cost)},
      {"evaluations", result.evaluations},
      {"simulations", result.simulations},
      {"refinement_steps", result.refinement_steps},
      {"wall_seconds", result.wall_seconds},
      {"stop_reason", result.stop_reason},
      {"cancelled", result.cancelled},
      {"filter",
       {{"half_length", result.filter.half_length},
        {"band", result.filter.band},
        {"dt", result.filter.dt},
        {"automatic", result.filter_chosen_automatically}}},
      {"torque_source", source_name(result.torque_source)},
      {"gains", gains_to_json(result)},
      {"residual_check", {{"residual_rms", number(result.residual_rms)}, {"noise_rms", number(result.noise_rms)}}},
      {"warnings", result.warnings},
      {"truth", truth_to_json(result.names, truth)},
  };
}

nlohmann::ordered_json history_to_json(const std::vector<HistoryRecord>& history, const std::vector<std::string>& names) {
  nlohmann::ordered_json records = nlohmann::ordered_json::array();
  for (const HistoryRecord& record : history) {
    records.push_back({{"index", record.index}, {"cost", number(record.cost)}, {"parameters", by_name(names, record.theta)}});
  }
  return records;
}

}  // namespace manipid::api

// requests.h — the service's request bodies (JSON, and CSV for datasets) mapped to core types,
// with every field validated up front so a job that is accepted can run.
//
// Every failure throws InputError whose field is a path into the body ("q", "tau[2]",
// "initial.m2", "simulation.noise.q_sigma"); malformed syntax throws ApiError(malformed_body).
// Everything a request leaves out defaults to the paper's settings (preset cedro2009), so
//     {"dataset_id": "ds_…", "preset": "cedro2009"}   is a complete identification request and
//     {"preset": "cedro2009"}                          a complete simulation request.
// The exact shapes are documented in api/openapi.yaml.
#pragma once

#include "manipid/api/log_format.h"
#include "manipid/api/ros2_bag.h"

#include "manipid/core/paper/identification.h"
#include "manipid/core/paper/presets.h"
#include "manipid/core/paper/simulation.h"
#include "manipid/core/signal/trajectory.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <string_view>

namespace manipid::api {

// ---- Datasets --------------------------------------------------------------------------

struct DatasetUpload {
  std::string name;        ///< optional label, ≤ 200 characters
  Trajectory trajectory;   ///< validated (Trajectory::validate)
};

/// JSON body: {"name"?, "t": [...] | "dt": s [, "t0": s], "q": [[joint 1 samples], ...],
/// "tau"?: [[...], ...], "ref"?: [[...], ...], "qd"?: [[...], ...], "qdd"?: [[...], ...]} — per-joint arrays, all of one
/// length; t strictly increasing, steps may jitter (stored as measured).
DatasetUpload dataset_from_json(const nlohmann::json& body);
/// The same from the body's text, read without a document of the whole body (the samples go
/// straight into arrays of doubles): syntax errors, numbers beyond a double and keys given
/// twice are ApiError/InputError as for any request body, every other error as above.
DatasetUpload dataset_from_json_text(std::string_view text);
/// CSV body: header t,q1..qn[,tau1..taun][,ref1..refn][,qd1..qdn][,qdd1..qddn] (what `manipid simulate`
/// and `manipid excitation` write), or a lab's log read through `format` (log_format.h: a column map,
/// the time and angle units).
DatasetUpload dataset_from_csv(std::string_view text, const LogFormat& format = {});
/// A ROS 2 bag (sqlite3 storage) of sensor_msgs/JointState (ros2_bag.h): t, q, and qd and tau when every
/// message has them.
DatasetUpload dataset_from_bag(std::string_view bytes, const BagOptions& options);

// ---- Simulations -----------------------------------------------------------------------

/// A closed-loop run of a preset robot (the paper's experiment by default).
struct SimulationSpec {
  std::string name;                 ///< label of the dataset it creates
  Preset preset;                    ///< with the chosen kinetic energy, gains and reference
  Parameters parameters;            ///< the "true" parameters simulated (default: the preset's)
  MeasurementNoise noise;           ///< default: none
};

/// {"preset"?: "cedro2009", "kinetic_energy"?: "complete"|"paper", "name"?,
///  "parameters"?: {"m2": 24.0, ...}, "kp"?: [...], "kd"?: [...],
///  "reference"?: {"step_times": [...], "amplitudes": [...], "half_length", "band"},
///  "duration"?: s, "dt"?: s, "relative_tolerance"?, "absolute_tolerance"?,
///  "noise"?: {"q_sigma", "tau_sigma", "tau_relative_sigma", "quantize_bits", "seed"}}
SimulationSpec simulation_from_json(const nlohmann::json& body);
/// Simulates and applies the noise. Throws std::runtime_error if the motion diverges.
Trajectory run_simulation(const SimulationSpec& spec, SimulationSummary* summary = nullptr);

// ---- Identifications -------------------------------------------------------------------

struct IdentificationSpec {
  std::string dataset_id;                  ///< empty when `simulation` is given
  std::optional<SimulationSpec> simulation;
  Preset preset;                           ///< the model identified (with kinetic energy)
  IdentificationOptions options;           ///< callbacks and cancel left empty
  /// True values the user knows ("truth"), shown beside the estimates: 2n entries in θ order,
  /// NaN where not given; empty when the request has none (a simulation's own parameters are
  /// then the truth, see `known_truth`).
  Eigen::VectorXd truth;
};

/// {"dataset_id": "ds_…" | "simulation": {<simulation request>},
///  "preset"?, "kinetic_energy"?, "method"?, "algorithm"?,
///  "free"?: ["m2", ...], "initial"?: {"m1": 50.1, ...}, "lower"?: {...}, "upper"?: {...},
///  "kp"?: [...], "kd"?: [...], "half_length"?: int | "auto", "band"?: number | "auto",
///  "torque_source"?: "auto"|"measured"|"reference", "weights"?: "unit"|"inverse-variance",
///  "max_evaluations"?, "max_seconds"?, "relative_x_tolerance"?, "relative_f_tolerance"?,
///  "output_error_iterations"?, "truth"?: {"m2": 20.0, ...}}
IdentificationSpec identification_from_json(const nlohmann::json& body);

/// The true values known for an identification: the request's "truth" when given, else the
/// parameters of the simulation that makes its data (`simulation`: the request's own, or the one
/// that made its dataset), else empty — data uploaded from elsewhere have no known truth.
Eigen::VectorXd known_truth(const IdentificationSpec& spec, const SimulationSpec* simulation);

/// Checks what needs the data: joint count matches the model, enough samples for the
/// filter (> 2M+1), ref columns for output-error/two-stage or torque_source=reference.
/// Throws InputError naming the field.
void check_against_data(const IdentificationSpec& spec, int joints, int samples, bool has_torque, bool has_reference);

}  // namespace manipid::api

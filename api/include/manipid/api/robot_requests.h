// robot_requests.h — the service's requests about URDF robots: uploads and identifications, validated up
// front with fields named as in the body (as requests.h does for the paper's preset).
#pragma once

#include "manipid/core/signal/resample.h"
#include "manipid/core/robot/excitation.h"
#include "manipid/core/robot/identification.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/payload.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace manipid::api {

// ---- Robots ----------------------------------------------------------------------------

/// A URDF upload: the document and how to read it.
struct RobotUpload {
  std::string name;  ///< default: the URDF's robot name
  std::string urdf;  ///< the document, kept byte for byte
  std::string base;  ///< default: the URDF's root link
  std::string tip;   ///< default: the only leaf below the base
};

/// JSON body: {"urdf": "<robot …>", "name"?, "base"?, "tip"?}.
RobotUpload robot_from_json(const nlohmann::json& body);

/// The upload parsed (robot/urdf.h): throws InputError with field "urdf" naming the element in its
/// message ("joint j3: ..."), or "base"/"tip" for those options.
struct ParsedRobot {
  robot::Model model;
  std::vector<std::string> warnings;
};
ParsedRobot parse_robot(const RobotUpload& upload);

/// How many parsed robots a process keeps (robot_cache.h): the last kRobotCacheEntries used, at most
/// kRobotCacheBytes of their documents.
inline constexpr std::size_t kRobotCacheEntries = 32;
inline constexpr std::size_t kRobotCacheBytes = 64u << 20;

// ---- Identifications of a URDF robot -----------------------------------------------------

/// The most runs one identification (or its validation) may name.
inline constexpr std::size_t kMostRuns = 16;

/// The robot and runs a job on a stored robot reads: a robot identification's and a payload identification's,
/// read from the body alike ("robot_id", "dataset_id" | "dataset_ids", "validation_dataset_id" |
/// "validation_dataset_ids").
struct RobotRuns {
  std::string robot_id;
  std::vector<std::string> dataset_ids;             ///< the training runs, 1 to kMostRuns
  std::string dataset_id;                           ///< the first of them (the job's dataset)
  std::vector<std::string> validation_dataset_ids;  ///< runs judged with the estimate; empty: no validation
  std::string validation_dataset_id;                ///< the first of them, empty: no validation
};

struct RobotIdentificationSpec : RobotRuns {
  robot::IdentificationOptions options;  ///< cancel left empty
  bool physical = false;
};

/// True when the identification request names a robot_id (the URDF robot path) rather than a preset.
bool names_a_robot(const nlohmann::json& body);

/// {"robot_id": "rb_…", "dataset_id": "ds_…" | "dataset_ids": ["ds_…", …],
///  "validation_dataset_id"?: "ds_…" | "validation_dataset_ids"?: [...],
///  "friction"?: "auto" (default: chosen by held-out prediction) | ["viscous", "coulomb", "offset"] ([] for none),
///  "armature"?: false, "physical"?: false, "trim"?: [start_s, end_s], "dt"?: s,
///  "half_length"?: int | "auto", "band"?: number | "auto" (the differentiation filter),
///  "comparison_cutoff"?: Hz | "auto", "ridge"?: number | "auto", "judge_cutoff"?: 5 (Hz), "judge_trim"?: 0.3 (s),
///  "torque_joints"?: [1-based joint numbers], "weights"?: "unit" | "per-joint"}. The paper preset's options
///  (method, algorithm, free, initial, kp, ...) are refused with the reason; so is a "preset" beside robot_id,
///  and the former comparison_half_length / comparison_band (naming comparison_cutoff).
RobotIdentificationSpec robot_identification_from_json(const nlohmann::json& body);

// ---- Payload identifications --------------------------------------------------------------

struct PayloadIdentificationSpec : RobotRuns {
  /// A succeeded robot_identification of the same robot whose result's point is the arm; empty: the URDF's
  /// values (with its viscous and Coulomb friction).
  std::string arm_job_id;
  robot::PayloadOptions options;  ///< cancel left empty
};

/// True when the identification request asks for a payload (it has a "payload" member).
bool asks_for_payload(const nlohmann::json& body);

/// {"payload": true, "robot_id": "rb_…", "dataset_id": "ds_…" | "dataset_ids": [...] (runs carrying the payload),
///  "arm_job_id"?: "job_…", "validation_dataset_id"? | "validation_dataset_ids"?, "known_mass"?: kg (> 0),
///  "known_centre_of_mass"?: [x, y, z] m (tip-link frame), "physical"?: false (a real rigid body), "trim"?, "dt"?, "comparison_cutoff"?: Hz (default the
///  judge's), "judge_cutoff"?, "judge_trim"?, "torque_joints"?: [1-based]} — the fields a robot identification
///  shares read by the same rules. The arm's own options (friction, armature, filters, ridge, weights) are
///  refused with the reason, as are the preset's.
PayloadIdentificationSpec payload_identification_from_json(const nlohmann::json& body);

// ---- Excitations -------------------------------------------------------------------------

struct ExcitationSpec {
  std::string robot_id;
  std::string name;                  ///< of the dataset it makes; default "excitation <robot> (<job>)"
  robot::ExcitationOptions options;  ///< cancel and progress left empty; the torque model not yet resolved
  nlohmann::json torque_parameters;  ///< the torque model as parameters_from_json takes it; null = the URDF's
  int periods = 1;                   ///< whole periods sampled
  double dt = 0.001;                 ///< s, the dataset's sample period
};

/// {"robot_id", "name"?, "period"?: 10, "harmonics"?: 5, "criterion"?: "condition"|"logdet",
///  "target"?: "arm"|"payload" (the base parameters, or a payload's ten on the tip link), "moving_joints"?: [joint
///  numbers, 1-based] (default all; the others hold the mean pose),
///  "max_acceleration"?: rad/s² (one number, or one per joint), "max_velocity"?: rad/s (default the URDF's),
///  "max_jerk"?: rad/s³ (default none), "max_torque"?: N m (default the URDF's efforts), "torque_parameters"?:
///  {an identification's result, or {"name": value} overrides} (default the URDF's), "start_pose"?: [rad …],
///  "position_margin"?: 0.1, "duration"?: s (whole periods; default one), "dt"?: 0.001, "friction"?: [...],
///  "armature"?, "seed"?, "max_seconds"?: 300, "max_evaluations"?: 8000}. What needs the robot (limits, the
///  joint counts, the torque model) is checked at submission by check_excitation and by the core when the
///  job runs.
ExcitationSpec excitation_from_json(const nlohmann::json& body);
/// The core's options for `spec` on `model`: the torque model resolved (InputError("torque_parameters")
/// for names the robot does not have).
robot::ExcitationOptions excitation_options(const ExcitationSpec& spec, const robot::Model& model);
/// Checks the request against the robot (its limits leave room, per-joint values match its joints), so
/// a job that is accepted can run.
void check_excitation(const ExcitationSpec& spec, const robot::Model& model);

/// Checks what needs the robot and the data: joint counts equal (naming both), torque present.
/// `field` names the dataset in messages ("dataset_id" or "validation_dataset_id").
void check_robot_data(int robot_joints, const std::string& robot_name, int data_joints, bool has_torque,
                      const std::string& field);

}  // namespace manipid::api

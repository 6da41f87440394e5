// job_memory.cpp — a job's shape from its request (each kind's, job_shapes.h) and the memory rule of job_memory.h.
#include "manipid/api/job_memory.h"

#include "manipid/api/job_kinds.h"

#include "manipid/api/requests.h"
#include "manipid/api/robot_requests.h"
#include "manipid/core/errors.h"

#include "job_shapes.h"
#include "json_fields.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace manipid::api {
namespace {

// The rule, measured (python3 bench/job_memory.py, release build, 40 s and 120 s runs at 1 ms;
// README "Reliability"): the rise of a job's peak RSS per sample and joint, and the figure used,
// about 1.3–1.5 times the largest measured, for what the measurement did not see (other filters,
// other options). A URDF robot's rows are built in blocks, so its parameters do not count.
constexpr double kSimulation = 160.0;          // measured 111–126 bytes
constexpr double kInputError = 224.0;          // measured 152–174 (a simulation before it included)
constexpr double kClosedLoop = 576.0;          // output-error and two-stage: measured 434–438
constexpr double kRobotIdentification = 288.0; // measured 198–209 (7 joints, 91 parameters, the held-out choice)
constexpr double kExcitation = 160.0;          // the dataset it writes, as a simulation's
constexpr double kPayloadIdentification = 112.0;  // measured 70–81 (7 joints, the URDF's arm; body n's 10 columns)
// What a job holds whatever its size (model, optimiser, result, a history batch): measured 1–2 MiB.
constexpr double kFixedBytes = 16.0 * (1 << 20);

/// Samples after a resampling onto a `dt` grid, when one is asked for (make_uniform).
long long resampled(const DatasetInfo& dataset, double dt) {
  if (dt <= 0.0 || dataset.samples < 2 || dataset.dt <= 0.0) return dataset.samples;
  return static_cast<long long>(std::ceil((dataset.samples - 1) * dataset.dt / dt)) + 1;
}

}  // namespace

namespace shapes {

JobShape simulation(const nlohmann::json& request, const DatasetLookup&, const RobotJointsLookup&) {
  const SimulationSpec spec = simulation_from_json(request);
  return {fields::simulation_samples(spec), spec.preset.model.joint_count(), kSimulation, "simulation", "duration"};
}

JobShape preset_identification(const nlohmann::json& request, const DatasetLookup& datasets, const RobotJointsLookup&) {
  const IdentificationSpec spec = identification_from_json(request);
  JobShape shape;
  shape.joints = spec.preset.model.joint_count();
  const bool closed_loop = spec.options.method != IdentificationMethod::input_error;
  shape.bytes_per_sample_joint = closed_loop ? kClosedLoop : kInputError;
  shape.work = std::string(to_string(spec.options.method)) + " identification";
  if (spec.simulation) {
    shape.samples = fields::simulation_samples(*spec.simulation);
    shape.field = "simulation";
    return shape;
  }
  shape.field = "dataset_id";
  if (const auto dataset = datasets(spec.dataset_id)) shape.samples = dataset->samples;
  return shape;
}

namespace {

/// A job that reads a stored robot's runs (RobotRuns), resampled onto `dt` when one is asked for: every training
/// and validation run's samples together.
JobShape robot_runs_shape(const RobotRuns& runs, double dt, const DatasetLookup& datasets, double bytes_per_sample_joint,
                          const char* work) {
  JobShape shape;
  shape.field = "dataset_id";
  std::vector<std::string> ids = runs.dataset_ids;
  ids.insert(ids.end(), runs.validation_dataset_ids.begin(), runs.validation_dataset_ids.end());
  for (const std::string& id : ids) {
    const auto dataset = datasets(id);
    if (!dataset) continue;
    shape.joints = std::max(shape.joints, dataset->joints);
    const long long samples = resampled(*dataset, dt);
    if (samples > dataset->samples) shape.field = "dt";
    shape.samples += samples;
  }
  shape.bytes_per_sample_joint = bytes_per_sample_joint;
  shape.work = work;
  return shape;
}

}  // namespace

JobShape robot_identification(const nlohmann::json& request, const DatasetLookup& datasets, const RobotJointsLookup&) {
  const RobotIdentificationSpec spec = robot_identification_from_json(request);
  return robot_runs_shape(spec, spec.options.preparation.uniform.dt, datasets, kRobotIdentification, "robot identification");
}

JobShape payload_identification(const nlohmann::json& request, const DatasetLookup& datasets, const RobotJointsLookup&) {
  const PayloadIdentificationSpec spec = payload_identification_from_json(request);
  return robot_runs_shape(spec, spec.options.preparation.uniform.dt, datasets, kPayloadIdentification,
                          "payload identification");
}

JobShape excitation(const nlohmann::json& request, const DatasetLookup&, const RobotJointsLookup& robots) {
  const ExcitationSpec spec = excitation_from_json(request);
  JobShape shape;
  shape.field = "duration";
  shape.samples = static_cast<long long>(std::ceil(spec.options.period * spec.periods / spec.dt)) + 1;
  shape.joints = robots(spec.robot_id).value_or(0);
  shape.bytes_per_sample_joint = kExcitation;
  shape.work = "excitation";
  // The criterion's workspace (robot/excitation_internal.h: CriterionWorkspace): the regressor Y and its
  // base columns Y_b stacked over N instants (N·n rows, P = layout.size(n) columns at most each), and for
  // the reported figures a column-scaled copy of Y_b and the SVD's own copy of it; the Gram matrix, its
  // scaled copy and the eigensolver's (P² each). Y alone is 768 MB for 100 joints and 20 harmonics, which
  // the per-sample rule did not see: a design estimated at 31 MiB peaked at 3.0 GB (this rule: 2.9 GiB).
  const double n = shape.joints;
  const double N = spec.options.samples > 0 ? spec.options.samples : std::max(200, 40 * spec.options.harmonics);
  const double P = spec.options.layout.size(shape.joints);
  shape.extra_bytes = 8.0 * (4.0 * N * n * P + 4.0 * P * P);
  char what[160];
  std::snprintf(what, sizeof what, "its criterion stacks a regressor of %.0f instants x %.0f joints x %.0f columns", N, n, P);
  shape.extra_what = what;
  shape.extra_field = "harmonics";
  return shape;
}

}  // namespace shapes

JobShape job_shape(JobKind kind, const nlohmann::json& request, const DatasetLookup& datasets,
                   const RobotJointsLookup& robots) {
  return job_kind_handler(kind).shape(request, datasets, robots);
}

std::size_t job_memory_bytes(const JobShape& shape) {
  return static_cast<std::size_t>(kFixedBytes + shape.extra_bytes +
                                  static_cast<double>(shape.samples) * shape.joints * shape.bytes_per_sample_joint);
}

void check_job_memory(const JobShape& shape, std::size_t budget) {
  const std::size_t need = job_memory_bytes(shape);
  if (need <= budget) return;
  if (shape.extra_bytes > static_cast<double>(shape.samples) * shape.joints * shape.bytes_per_sample_joint) {
    throw InputError(shape.extra_field, "this " + shape.work + " would hold about " + describe_bytes(need) +
                                            " of memory while it runs (" + shape.extra_what +
                                            "); this server runs jobs within " + describe_bytes(budget) +
                                            " (--job-memory): use fewer harmonics, or ask for a larger --job-memory");
  }
  throw InputError(shape.field, "this " + shape.work + " would hold about " + describe_bytes(need) +
                                    " of memory while it runs (" + std::to_string(shape.samples) + " samples of " +
                                    std::to_string(shape.joints) + " joints); this server runs jobs within " +
                                    describe_bytes(budget) +
                                    " (--job-memory): use fewer samples, or ask for a larger --job-memory");
}

std::string describe_bytes(std::size_t bytes) {
  char text[32];
  const double value = static_cast<double>(bytes);
  if (value >= 1024.0 * 1024 * 1024) {
    std::snprintf(text, sizeof text, "%.1f GiB", value / (1024.0 * 1024 * 1024));
  } else {
    std::snprintf(text, sizeof text, "%.0f MiB", std::max(1.0, value / (1024.0 * 1024)));
  }
  return text;
}

}  // namespace manipid::api

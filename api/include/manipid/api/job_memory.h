// job_memory.h — the memory a job holds while it runs, estimated from the shape of its data
// (samples, joints, what it does): the one rule the door (422 naming the field when a job could
// never fit in --job-memory) and the worker pool (a job starts when its estimate fits beside
// the jobs running, else waits) both apply, so no single request can exhaust the machine.
#pragma once

#include "manipid/api/records.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <functional>
#include <optional>
#include <string>

namespace manipid::api {

/// What sets a job's memory: the samples it works on (after any resampling; every dataset it
/// reads together), its joints, and what it does with them — the bytes it holds per sample and
/// joint, measured per kind of work (job_memory.cpp).
struct JobShape {
  long long samples = 0;
  int joints = 0;
  double bytes_per_sample_joint = 0.0;
  std::string work;   ///< what it does, for messages: "simulation", "two-stage identification"
  std::string field;  ///< the request's field that sets the size: "duration", "dataset_id", "dt"
  /// Working memory that does not grow with the samples (an excitation's criterion: its stacked regressor
  /// grows with joints² and harmonics), bytes, and what it is, for messages; `extra_field` the request's
  /// field that sets it ("harmonics").
  double extra_bytes = 0.0;
  std::string extra_what{};
  std::string extra_field{};
};

/// A dataset's description by id (the store's or the service's), or nullopt when there is none.
using DatasetLookup = std::function<std::optional<DatasetInfo>(const std::string& id)>;
/// A stored robot's joint count by id, or nullopt when there is none.
using RobotJointsLookup = std::function<std::optional<int>(const std::string& id)>;

/// The shape of a job from its request body (as submitted or as stored) and what it names. A
/// dataset or robot that does not exist counts as empty: the submission refuses it by name, a run
/// fails on it. Throws what the request parsers throw for a request they refuse.
JobShape job_shape(JobKind kind, const nlohmann::json& request, const DatasetLookup& datasets,
                   const RobotJointsLookup& robots);

/// Bytes the job holds at its peak, at most: samples × joints × bytes_per_sample_joint, the shape's
/// extra_bytes and a fixed part. bench/job_memory.py measures the release build's peak against it.
std::size_t job_memory_bytes(const JobShape& shape);

/// Throws InputError(shape.field, …) when the job's estimate is above `budget` (--job-memory):
/// a job that could never start.
void check_job_memory(const JobShape& shape, std::size_t budget);

/// "1.5 GiB", "320 MiB": a byte count for messages and logs.
std::string describe_bytes(std::size_t bytes);

}  // namespace manipid::api

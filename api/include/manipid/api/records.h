// records.h — what the service keeps and answers with: datasets, jobs, cost-history entries
// and pages of them. Plain structs shared by the routes (api/) and the store (server/).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace manipid::api {

enum class JobState { queued, running, succeeded, failed, cancelled };
const char* to_string(JobState state);
std::optional<JobState> parse_job_state(std::string_view text);
inline bool is_terminal(JobState state) {
  return state == JobState::succeeded || state == JobState::failed || state == JobState::cancelled;
}

/// What a job does. `identification` is the paper's preset model (a cost minimised step by step, or input-error);
/// `robot_identification` a stored URDF robot's base parameters (one least-squares solve);
/// `payload_identification` a payload on a stored robot's tip link (robot/payload.h). Each kind's handling
/// is one entry of job_kinds.h (api) and of the runner's table (server/jobs/job_runner.cpp). The store keeps
/// the enumerator's position nowhere: it writes the names below.
enum class JobKind { simulation, identification, excitation, robot_identification, payload_identification };
/// Every kind, in declaration order.
inline constexpr JobKind kJobKinds[] = {JobKind::simulation, JobKind::identification, JobKind::excitation,
                                        JobKind::robot_identification, JobKind::payload_identification};
const char* to_string(JobKind kind);
std::optional<JobKind> parse_job_kind(std::string_view text);

/// Whose datasets, robots and jobs a call sees: one owner's (the name of a non-admin token of
/// `manipid serve --token-file`), or every owner's (std::nullopt, all_owners: an admin token, a
/// server without named tokens, the workers and recovery). What is outside it is answered as missing.
using OwnerScope = std::optional<std::string>;
inline const OwnerScope all_owners = std::nullopt;

struct DatasetInfo {
  std::string id;           ///< "ds_" + 16 hex digits
  std::string name;
  std::string created_at;   ///< RFC 3339 UTC, millisecond precision
  std::string owner;        ///< the name of the token that made it (a job's output: its job's); "" without named tokens
  std::string source_job;   ///< the simulation job that made it, else empty
  int joints = 0;
  int samples = 0;
  double dt = 0.0;          ///< s: the sample period (uniform data) or the median step (jittery data)
  bool uniform = true;      ///< every step equals dt (to 1e-6); else stored as measured, resampled when used
  bool has_torque = false;
  bool has_reference = false;
  bool has_rates = false;   ///< qd1..qdn columns
  bool has_accelerations = false;  ///< qdd1..qddn columns
};

/// A robot uploaded as a URDF: what the store keeps beside the document itself.
struct RobotInfo {
  std::string id;           ///< "rb_" + 16 hex digits
  std::string name;
  std::string created_at;   ///< RFC 3339 UTC
  std::string owner;        ///< the name of the token that uploaded it; "" without named tokens
  std::string base, tip;    ///< the links asked for at upload (empty: the URDF's root, its only leaf)
  int joints = 0;
  std::string summary;      ///< the robot resource's description as JSON text (joints, links, parameters)
};

struct JobInfo {
  std::string id;           ///< "job_" + 16 hex digits
  JobKind kind = JobKind::identification;
  JobState state = JobState::queued;
  std::string created_at, started_at, finished_at;  ///< RFC 3339 UTC; empty until it happens
  std::string request;      ///< the request body as accepted (JSON text)
  std::string dataset_id;   ///< input (identification) or output (simulation, excitation); may be empty
  std::string robot_id;     ///< the URDF robot it works on (robot identifications, excitations); may be empty
  std::string validation_dataset_id;  ///< a second run the result predicts; may be empty
  long evaluations = 0;     ///< progress: cost evaluations so far
  std::optional<double> best_cost;
  bool cancel_requested = false;
  int attempts = 0;         ///< times a worker started it (> 1 after a restart)
  std::string worker;       ///< while running: the process that holds its lease, "HOST:PID"
  std::string owner;        ///< the name of the token that submitted it; "" without named tokens
  std::string result;       ///< JSON text when succeeded
  std::string error;        ///< problem JSON text when failed
};

struct HistoryEntry {
  long index = 0;
  double cost = 0.0;
  std::vector<double> theta;  ///< all parameters, θ order (m1..mn, l1..ln)
};

/// A cost history thinned for drawing: every stride-th entry (index order), plus always the
/// first, the last and the best (lowest cost). `total` counts every stored entry.
struct HistoryOverview {
  long total = 0;
  long stride = 1;
  std::optional<long> best_index;  ///< none while the history is empty
  std::vector<HistoryEntry> items;
};

/// The stride s = ceil(count / max_points) that thins `count` samples to about max_points;
/// 1 when count ≤ max_points or max_points ≤ 0. Stores thin histories by it, plots their series.
long thinning_stride(long count, long max_points);

struct PageRequest {
  int page_size = 50;        ///< 1..1000 (0 means 50)
  std::string page_token;    ///< opaque; empty = first page
};

template <class T>
struct Page {
  std::vector<T> items;
  std::string next_page_token;  ///< empty only on the last page
};

struct JobFilter {
  std::optional<JobState> state;
  std::optional<JobKind> kind;
  std::string robot_id;  ///< empty: any job; else only the jobs on this robot
};

/// An Idempotency-Key header with the fingerprint (SHA-256 hex) of the request it came with.
struct IdempotencyKey {
  std::string key;
  std::string fingerprint;
};

}  // namespace manipid::api

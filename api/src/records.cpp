// records.cpp — the names of job states and kinds as they appear in JSON, query strings and
// the store, and the thinning stride of long series (records.h). Parsing is exact (lower case,
// no trimming): these are API tokens.
#include "manipid/api/records.h"

namespace manipid::api {

const char* to_string(JobState state) {
  switch (state) {
    case JobState::queued: return "queued";
    case JobState::running: return "running";
    case JobState::succeeded: return "succeeded";
    case JobState::failed: return "failed";
    case JobState::cancelled: return "cancelled";
  }
  return "failed";  // unreachable for valid enumerators
}

std::optional<JobState> parse_job_state(std::string_view text) {
  for (JobState state : {JobState::queued, JobState::running, JobState::succeeded, JobState::failed,
                         JobState::cancelled}) {
    if (text == to_string(state)) return state;
  }
  return std::nullopt;
}

const char* to_string(JobKind kind) {
  switch (kind) {
    case JobKind::simulation: return "simulation";
    case JobKind::identification: return "identification";
    case JobKind::excitation: return "excitation";
    case JobKind::robot_identification: return "robot_identification";
    case JobKind::payload_identification: return "payload_identification";
  }
  return "identification";  // unreachable for valid enumerators
}

std::optional<JobKind> parse_job_kind(std::string_view text) {
  for (JobKind kind : kJobKinds) {
    if (text == to_string(kind)) return kind;
  }
  return std::nullopt;
}

long thinning_stride(long count, long max_points) {
  return max_points <= 0 || count <= max_points ? 1 : (count + max_points - 1) / max_points;
}

}  // namespace manipid::api

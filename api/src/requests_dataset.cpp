// requests_dataset.cpp — dataset uploads (requests.h): the JSON form with per-joint arrays and
// either explicit times t or a period dt, and the CSV form `manipid simulate` writes. Both end
// in a validated Trajectory, so the same data gives the same dataset whichever form it came in.
#include "manipid/api/csv.h"
#include "json_fields.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace manipid::api {
namespace {

using fields::Json;

/// One joint-major block ("q", "tau" or "ref"): an array of per-joint arrays of finite
/// numbers, all `samples` long (the first joint sets it when `samples` < 0).
struct JointBlock {
  const char* name;
  Eigen::MatrixXd values;  ///< samples × joints
};

/// What the sample count was measured against, for messages: "t" or "q[0]".
struct SampleCount {
  long samples = -1;
  std::string source;
};

std::string samples_text(std::size_t count) {
  return std::to_string(count) + (count == 1 ? " sample" : " samples");
}

Eigen::MatrixXd read_block(const Json& value, const std::string& path, int expected_joints, SampleCount& count) {
  if (!value.is_array()) {
    throw InputError(path, path + " must be an array of per-joint arrays ([[joint 1 samples], [joint 2 samples], ...]), got " +
                               fields::describe(value));
  }
  const std::size_t joints = value.size();
  if (joints == 0) throw InputError(path, path + " is empty: it needs one array of samples per joint");
  limits::check_joints(static_cast<int>(std::min<std::size_t>(joints, std::numeric_limits<int>::max())), path, path);
  if (expected_joints > 0 && joints != static_cast<std::size_t>(expected_joints)) {
    throw InputError(path, path + " has " + std::to_string(joints) + " joints, expected " +
                               std::to_string(expected_joints) + " (as q)");
  }
  // Every joint's length is checked before anything is allocated: sizing the matrix from
  // joint 0 alone let a 100 kB body (one long joint, many empty ones) ask for gigabytes.
  if (value[0].is_array()) {
    const bool counted = count.samples >= 0;
    const std::size_t expected = counted ? static_cast<std::size_t>(count.samples) : value[0].size();
    const std::string source = counted ? count.source : fields::element_path(path, 0);
    for (std::size_t joint = 0; joint < joints; ++joint) {
      if (!value[joint].is_array() || value[joint].size() == expected) continue;
      const std::string joint_path = fields::element_path(path, joint);
      std::string message = joint_path + " has " + samples_text(value[joint].size()) + ", expected " +
                            std::to_string(expected) + " (as " + source + ")";
      if (joints == expected) message += "; " + path + " must hold one array per joint, not one per sample";
      throw InputError(joint_path, message);
    }
  }
  Eigen::MatrixXd values;
  for (std::size_t joint = 0; joint < joints; ++joint) {
    const std::string joint_path = fields::element_path(path, joint);
    const Json& signal = value[joint];
    if (!signal.is_array()) {
      throw InputError(joint_path, joint_path + " must be an array of numbers (the samples of joint " +
                                       std::to_string(joint + 1) + "), got " + fields::describe(signal));
    }
    const std::size_t size = signal.size();
    if (count.samples < 0) {
      if (static_cast<double>(size) > fields::max_samples) {
        throw InputError(joint_path, joint_path + " has " + samples_text(size) + "; at most " +
                                         std::to_string(static_cast<long long>(fields::max_samples)) + " are allowed");
      }
      count.samples = static_cast<long>(size);
      count.source = joint_path;
    }
    if (size != static_cast<std::size_t>(count.samples)) {
      std::string message = joint_path + " has " + samples_text(size) + ", expected " +
                            std::to_string(count.samples) + " (as " + count.source + ")";
      // The usual cause: sample-major rows [[q1, q2, ...], ...] instead of one array per joint.
      if (joints == static_cast<std::size_t>(count.samples)) {
        message += "; " + path + " must hold one array per joint, not one per sample";
      }
      throw InputError(joint_path, message);
    }
    if (joint == 0) values.resize(static_cast<Eigen::Index>(size), static_cast<Eigen::Index>(joints));
    for (std::size_t sample = 0; sample < size; ++sample) {
      const Json& element = signal[sample];
      // Checked inline (not via read_number) because this loop runs for every sample.
      if (!element.is_number() || !std::isfinite(element.get<double>())) {
        fields::read_number(element, fields::element_path(joint_path, sample));  // throws with the message
      }
      values(static_cast<Eigen::Index>(sample), static_cast<Eigen::Index>(joint)) = element.get<double>();
    }
  }
  return values;
}

Eigen::VectorXd read_times(const Json& value, SampleCount& count) {
  if (!value.is_array()) throw InputError("t", "t must be an array of sample times in s, got " + fields::describe(value));
  if (static_cast<double>(value.size()) > fields::max_samples) {
    throw InputError("t", "t has " + samples_text(value.size()) + "; at most " +
                              std::to_string(static_cast<long long>(fields::max_samples)) + " are allowed");
  }
  Eigen::VectorXd t(static_cast<Eigen::Index>(value.size()));
  for (std::size_t i = 0; i < value.size(); ++i) {
    t[static_cast<Eigen::Index>(i)] = fields::read_number(value[i], fields::element_path("t", i));
  }
  count.samples = static_cast<long>(value.size());
  count.source = "t";
  return t;
}

}  // namespace

DatasetUpload dataset_from_json(const nlohmann::json& body) {
  const fields::ObjectFields object(body, "", {"name", "t", "dt", "t0", "q", "tau", "ref", "qd", "qdd"});
  DatasetUpload upload;
  if (const Json* name = object.find("name")) upload.name = fields::read_label(*name, "name");

  const Json* times = object.find("t");
  const Json* period = object.find("dt");
  if (times && period) throw InputError("dt", "give either t (the sample times) or dt (the sample period), not both");
  if (!times && !period) {
    throw InputError("t", "missing t: give the sample times t or the sample period dt (with an optional t0)");
  }
  if (times && object.has("t0")) throw InputError("t0", "t0 goes with dt; with t the times are given in full");
  const Json* q = object.find("q");
  if (!q) throw InputError("q", "missing q: the joint angles, one array of samples per joint");

  Trajectory& trajectory = upload.trajectory;
  SampleCount count;
  if (times) trajectory.t = read_times(*times, count);
  trajectory.q = read_block(*q, "q", 0, count);
  const int joints = static_cast<int>(trajectory.q.cols());
  if (const Json* tau = object.find("tau")) trajectory.tau = read_block(*tau, "tau", joints, count);
  if (const Json* ref = object.find("ref")) trajectory.ref = read_block(*ref, "ref", joints, count);
  if (const Json* qd = object.find("qd")) trajectory.qd = read_block(*qd, "qd", joints, count);
  if (const Json* qdd = object.find("qdd")) trajectory.qdd = read_block(*qdd, "qdd", joints, count);

  const int blocks = static_cast<int>(object.has("tau") + object.has("ref") + object.has("qd") + object.has("qdd")) + 1;
  limits::check_dataset_size(count.samples, joints, blocks, count.source, count.source);
  if (count.samples < 2) {
    throw InputError(count.source, "a dataset needs at least 2 samples, " + count.source + " has " +
                                       samples_text(static_cast<std::size_t>(count.samples)));
  }
  if (period) {
    const double dt = fields::read_positive(*period, "dt", fields::infinity, " s");
    const double t0 = object.has("t0") ? fields::read_number(*object.find("t0"), "t0") : 0.0;
    // t0 + i·dt rather than a running sum: no accumulated rounding, the same as a CSV that
    // printed these times.
    trajectory.t.resize(count.samples);
    for (Eigen::Index i = 0; i < trajectory.t.size(); ++i) trajectory.t[i] = t0 + static_cast<double>(i) * dt;
  }
  try {
    trajectory.validate();
  } catch (const InputError& error) {
    // With dt the times were computed, so a bad clock (dt lost against a huge t0) is dt's fault.
    if (period && error.field() == "t") throw InputError("dt", error.what());
    throw;
  }
  return upload;
}

DatasetUpload dataset_from_csv(std::string_view text) {
  DatasetUpload upload;
  upload.trajectory = trajectory_from_csv(parse_csv(text));
  return upload;
}

}  // namespace manipid::api

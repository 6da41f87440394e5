// requests_dataset.cpp — dataset uploads (requests.h): the JSON form with per-joint arrays and
// either explicit times t or a period dt, and the CSV form `manipid simulate` writes. Both end
// in a validated Trajectory, so the same data gives the same dataset whichever form it came in.
// JSON text is read with nlohmann's SAX interface: the samples go straight into arrays of
// doubles, never into a document of the whole body (16 bytes and more per number).
#include "manipid/api/csv.h"
#include "manipid/api/problem.h"
#include "json_fields.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <utility>

namespace manipid::api {
namespace {

/// The sample arrays of the body — t, and each joint of q, tau, ref, qd, qdd — as they came:
/// what the checks below need (sizes, types, the first entry that is not a number), never a
/// document of every number.
struct Series {
  std::vector<double> values;  ///< the entries, while they are numbers
  std::size_t size = 0;        ///< entries in all
  std::size_t bad = std::numeric_limits<std::size_t>::max();  ///< the first entry that is not a finite number
  fields::Json bad_value;
  bool has_bad() const { return bad != std::numeric_limits<std::size_t>::max(); }
};

/// t or a block, or one joint of a block: an array (of numbers for t and a joint, of joints for
/// a block) or, when it is anything else, that value itself.
struct Streamed {
  bool is_array = false;
  fields::Json value;                    ///< when not an array
  Series series;                 ///< t, a joint
  std::vector<Streamed> joints;  ///< a block
  std::size_t size() const { return joints.empty() ? series.size : joints.size(); }
};

constexpr const char* block_names[] = {"q", "tau", "ref", "qd", "qdd"};

bool is_block(std::string_view key) {
  return std::find(std::begin(block_names), std::end(block_names), key) != std::end(block_names);
}

/// The body's members: the small ones as JSON (with a null standing for t and the blocks, so
/// ObjectFields sees every key), t and the blocks in `streamed`.
struct Members {
  fields::Json object = fields::Json::object();
  std::map<std::string, Streamed, std::less<>> streamed;
};

Series series_from_json(const fields::Json& value) {
  Series series;
  series.size = value.size();
  series.values.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    const fields::Json& element = value[i];
    if (!element.is_number() || !std::isfinite(element.get<double>())) {
      series.bad = i;
      series.bad_value = element;
      break;
    }
    series.values.push_back(element.get<double>());
  }
  return series;
}

/// A document (the unit tests', or any caller's) in the form the SAX reader produces.
Members members_from_json(const fields::Json& body) {
  Members members;
  if (!body.is_object()) {
    members.object = body;  // ObjectFields refuses it with the usual words
    return members;
  }
  for (const auto& [key, value] : body.items()) {
    if (key != "t" && !is_block(key)) {
      members.object[key] = value;
      continue;
    }
    members.object[key] = nullptr;
    Streamed& streamed = members.streamed[key];
    streamed.is_array = value.is_array();
    if (!value.is_array()) {
      streamed.value = value;
    } else if (key == "t") {
      streamed.series = series_from_json(value);
    } else {
      for (const fields::Json& joint : value) {
        Streamed& entry = streamed.joints.emplace_back();
        entry.is_array = joint.is_array();
        if (entry.is_array) {
          entry.series = series_from_json(joint);
        } else {
          entry.value = joint;
        }
      }
    }
  }
  return members;
}

/// nlohmann's SAX interface (json_sax): the body's structure on a stack of frames, the numbers
/// of t and of each joint appended to their Series as they are read, everything else (the small
/// members, and values in the wrong place, for the messages) built as JSON. Keys seen twice in
/// any object are refused as parse_request refuses them; syntax errors and numbers beyond a
/// double answer as parse_request answers them. Every other check waits for the end of the
/// body, so a body that is not JSON is answered as such whatever it holds.
class DatasetReader {
 public:
  using number_integer_t = fields::Json::number_integer_t;
  using number_unsigned_t = fields::Json::number_unsigned_t;
  using number_float_t = fields::Json::number_float_t;
  using string_t = fields::Json::string_t;
  using binary_t = fields::Json::binary_t;

  bool null() { return scalar(nullptr, fields::Json(nullptr)); }
  bool boolean(bool value) { return scalar(nullptr, fields::Json(value)); }
  bool number_integer(number_integer_t value) {
    const double number = static_cast<double>(value);
    return scalar(&number, fields::Json(value));
  }
  bool number_unsigned(number_unsigned_t value) {
    const double number = static_cast<double>(value);
    return scalar(&number, fields::Json(value));
  }
  bool number_float(number_float_t value, const string_t&) { return scalar(&value, fields::Json(value)); }
  bool string(string_t& value) { return scalar(nullptr, fields::Json(std::move(value))); }
  bool binary(binary_t&) { return scalar(nullptr, fields::Json()); }  // never in JSON text
  bool start_object(std::size_t) { return open(true); }
  bool start_array(std::size_t) { return open(false); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }
  bool key(string_t& key) {
    Frame& frame = frames_.back();
    if (!frame.keys.insert(key).second) fields::throw_duplicate_key(path_of(frames_.size() - 1), key);
    frame.key = key;
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception& error) {
    fields::throw_parse_failure(error, current_path());
  }

  /// The members, once the whole body was read.
  Members& members() {
    if (!top_is_object_) throw ApiError(ProblemKind::malformed_body, "expected a JSON object at the top level", "body");
    return members_;
  }

 private:
  /// Where a frame's values go.
  enum class Kind {
    top,      ///< the body's members
    block,    ///< a block's joints
    series,   ///< numbers, into `series`
    capture,  ///< built as JSON into `container`
    skip,     ///< read and dropped (inside a value already refused)
  };
  struct Frame {
    Kind kind;
    bool object;
    std::size_t count = 0;  ///< an array's entries so far
    std::set<std::string> keys;
    std::string key;  ///< an object's current key
    fields::Json* container = nullptr;
    Streamed* streamed = nullptr;
    Series* series = nullptr;
  };

  static Frame make_frame(Kind kind, bool object, fields::Json* container = nullptr, Streamed* streamed = nullptr,
                          Series* series = nullptr) {
    Frame frame{kind, object, 0, {}, {}, container, streamed, series};
    return frame;
  }

  /// The path of the value at frames_[depth] ("" for the body).
  std::string path_of(std::size_t depth) const {
    std::string path;
    for (std::size_t i = 0; i < depth; ++i) {
      path = frames_[i].object ? fields::member_path(path, frames_[i].key) : fields::element_path(path, frames_[i].count - 1);
    }
    return path;
  }
  /// The path of the value being read now.
  std::string current_path() const {
    if (frames_.empty()) return "";
    const Frame& frame = frames_.back();
    const std::string parent = path_of(frames_.size() - 1);
    return frame.object ? fields::member_path(parent, frame.key) : fields::element_path(parent, frame.count);
  }

  /// A number (with `number`) or another scalar arriving in the innermost frame.
  bool scalar(const double* number, fields::Json value) {
    if (frames_.empty()) return true;  // a scalar body: refused at the end
    Frame& frame = frames_.back();
    switch (frame.kind) {
      case Kind::series: {
        Series& series = *frame.series;
        if (!series.has_bad()) {
          if (number) {
            series.values.push_back(*number);
          } else {
            series.bad = series.size;
            series.bad_value = std::move(value);
          }
        }
        ++series.size;
        ++frame.count;
        return true;
      }
      case Kind::skip:
        if (!frame.object) ++frame.count;
        return true;
      default: *place(frame) = std::move(value); return true;
    }
  }

  /// A slot for the next value in a top, block or capture frame (which counts it).
  fields::Json* place(Frame& frame) {
    // Values built as JSON are few in a dataset (a name, dt, t0; a wrong value for a message):
    // a member holding many is refused before its document outgrows the body.
    if (++captured_values_ > max_captured_values) {
      const std::string member = frames_[0].object ? frames_[0].key : std::string("body");
      throw InputError(member, fields::field_name(member) + " holds more than " + std::to_string(max_captured_values) +
                                   " values; only t, q, tau, ref, qd and qdd carry samples");
    }
    switch (frame.kind) {
      case Kind::top: {
        members_.object[frame.key] = nullptr;
        if (frame.key == "t" || is_block(frame.key)) return &members_.streamed[frame.key].value;
        return &members_.object[frame.key];
      }
      case Kind::block: {
        ++frame.count;
        return &frame.streamed->joints.emplace_back().value;
      }
      default:
        if (frame.object) return &(*frame.container)[frame.key];
        ++frame.count;
        frame.container->push_back(nullptr);
        return &frame.container->back();
    }
  }

  bool open(bool object) {
    if (frames_.size() == max_depth) {
      throw ApiError(ProblemKind::malformed_body,
                     "the body nests arrays or objects more than " + std::to_string(max_depth) + " deep; a dataset needs 3",
                     "body");
    }
    if (frames_.empty()) {
      top_is_object_ = object;
      frames_.push_back(make_frame(object ? Kind::top : Kind::skip, object));
      return true;
    }
    Frame& frame = frames_.back();
    // An array of numbers where the samples go: t, or a joint of a block.
    if (!object && frame.kind == Kind::top && (frame.key == "t" || is_block(frame.key))) {
      members_.object[frame.key] = nullptr;
      Streamed& streamed = members_.streamed[frame.key];
      streamed.is_array = true;
      if (frame.key == "t") {
        frames_.push_back(make_frame(Kind::series, false, nullptr, &streamed, &streamed.series));
      } else {
        frames_.push_back(make_frame(Kind::block, false, nullptr, &streamed));
      }
      return true;
    }
    if (!object && frame.kind == Kind::block) {
      ++frame.count;
      Streamed& joint = frame.streamed->joints.emplace_back();
      joint.is_array = true;
      frames_.push_back(make_frame(Kind::series, false, nullptr, &joint, &joint.series));
      return true;
    }
    if (frame.kind == Kind::series) {
      Series& series = *frame.series;
      const bool first_bad = !series.has_bad();
      if (first_bad) {
        series.bad = series.size;
        series.bad_value = object ? fields::Json::object() : fields::Json::array();
      }
      ++series.size;
      ++frame.count;
      fields::Json* container = first_bad ? &series.bad_value : nullptr;
      frames_.push_back(make_frame(first_bad ? Kind::capture : Kind::skip, object, container));
      return true;
    }
    if (frame.kind == Kind::skip) {
      if (!frame.object) ++frame.count;
      frames_.push_back(make_frame(Kind::skip, object));
      return true;
    }
    fields::Json* slot = place(frame);
    *slot = object ? fields::Json::object() : fields::Json::array();
    frames_.push_back(make_frame(Kind::capture, object, slot));
    return true;
  }

  bool close() {
    Frame& frame = frames_.back();
    // A joint's array is complete: give back what doubling the capacity took.
    if (frame.kind == Kind::series) frame.series->values.shrink_to_fit();
    frames_.pop_back();
    return true;
  }

  static constexpr std::size_t max_depth = 64;
  static constexpr std::size_t max_captured_values = 100'000;

  std::vector<Frame> frames_;
  std::size_t captured_values_ = 0;
  bool top_is_object_ = false;
  Members members_;
};

/// What the sample count was measured against, for messages: "t" or "q[0]".
struct SampleCount {
  long samples = -1;
  std::string source;
};

std::string samples_text(std::size_t count) {
  return std::to_string(count) + (count == 1 ? " sample" : " samples");
}

/// Throws read_number's message for the first entry of `series` that is not a finite number.
void check_numbers(const Series& series, const std::string& path) {
  if (series.has_bad()) fields::read_number(series.bad_value, fields::element_path(path, series.bad));
}

Eigen::MatrixXd read_block(Streamed& value, const std::string& path, int expected_joints, SampleCount& count) {
  if (!value.is_array) {
    throw InputError(path, path + " must be an array of per-joint arrays ([[joint 1 samples], [joint 2 samples], ...]), got " +
                               fields::describe(value.value));
  }
  const std::size_t joints = value.joints.size();
  if (joints == 0) throw InputError(path, path + " is empty: it needs one array of samples per joint");
  limits::check_joints(static_cast<int>(std::min<std::size_t>(joints, std::numeric_limits<int>::max())), path, path);
  if (expected_joints > 0 && joints != static_cast<std::size_t>(expected_joints)) {
    throw InputError(path, path + " has " + std::to_string(joints) + " joints, expected " +
                               std::to_string(expected_joints) + " (as q)");
  }
  // Every joint's length is checked before anything is allocated: sizing the matrix from
  // joint 0 alone let a 100 kB body (one long joint, many empty ones) ask for gigabytes.
  if (value.joints[0].is_array) {
    const bool counted = count.samples >= 0;
    const std::size_t expected = counted ? static_cast<std::size_t>(count.samples) : value.joints[0].series.size;
    const std::string source = counted ? count.source : fields::element_path(path, 0);
    for (std::size_t joint = 0; joint < joints; ++joint) {
      if (!value.joints[joint].is_array || value.joints[joint].series.size == expected) continue;
      const std::string joint_path = fields::element_path(path, joint);
      std::string message = joint_path + " has " + samples_text(value.joints[joint].series.size) + ", expected " +
                            std::to_string(expected) + " (as " + source + ")";
      if (joints == expected) message += "; " + path + " must hold one array per joint, not one per sample";
      throw InputError(joint_path, message);
    }
  }
  for (std::size_t joint = 0; joint < joints; ++joint) {
    const std::string joint_path = fields::element_path(path, joint);
    const Streamed& signal = value.joints[joint];
    if (!signal.is_array) {
      throw InputError(joint_path, joint_path + " must be an array of numbers (the samples of joint " +
                                       std::to_string(joint + 1) + "), got " + fields::describe(signal.value));
    }
    const std::size_t size = signal.series.size;
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
    check_numbers(signal.series, joint_path);
  }
  // Joint by joint into the matrix, each joint's array freed once copied.
  Eigen::MatrixXd values(count.samples, static_cast<Eigen::Index>(joints));
  for (std::size_t joint = 0; joint < joints; ++joint) {
    std::vector<double>& signal = value.joints[joint].series.values;
    values.col(static_cast<Eigen::Index>(joint)) = Eigen::Map<const Eigen::VectorXd>(signal.data(), count.samples);
    std::vector<double>().swap(signal);
  }
  return values;
}

Eigen::VectorXd read_times(Streamed& value, SampleCount& count) {
  if (!value.is_array) throw InputError("t", "t must be an array of sample times in s, got " + fields::describe(value.value));
  const std::size_t size = value.series.size;
  if (static_cast<double>(size) > fields::max_samples) {
    throw InputError("t", "t has " + samples_text(size) + "; at most " +
                              std::to_string(static_cast<long long>(fields::max_samples)) + " are allowed");
  }
  check_numbers(value.series, "t");
  Eigen::VectorXd t = Eigen::Map<const Eigen::VectorXd>(value.series.values.data(), static_cast<Eigen::Index>(size));
  std::vector<double>().swap(value.series.values);
  count.samples = static_cast<long>(size);
  count.source = "t";
  return t;
}

DatasetUpload dataset_from_members(Members& members) {
  const fields::ObjectFields object(members.object, "", {"name", "t", "dt", "t0", "q", "tau", "ref", "qd", "qdd"});
  DatasetUpload upload;
  if (const fields::Json* name = object.find("name")) upload.name = fields::read_label(*name, "name");

  const bool times = object.has("t");
  const fields::Json* period = object.find("dt");
  if (times && period) throw InputError("dt", "give either t (the sample times) or dt (the sample period), not both");
  if (!times && !period) {
    throw InputError("t", "missing t: give the sample times t or the sample period dt (with an optional t0)");
  }
  if (times && object.has("t0")) throw InputError("t0", "t0 goes with dt; with t the times are given in full");
  if (!object.has("q")) throw InputError("q", "missing q: the joint angles, one array of samples per joint");

  Trajectory& trajectory = upload.trajectory;
  SampleCount count;
  if (times) trajectory.t = read_times(members.streamed.at("t"), count);
  trajectory.q = read_block(members.streamed.at("q"), "q", 0, count);
  const int joints = static_cast<int>(trajectory.q.cols());
  const auto optional_block = [&](const char* name, Eigen::MatrixXd& block) {
    if (const auto found = members.streamed.find(name); found != members.streamed.end()) {
      block = read_block(found->second, name, joints, count);
    }
  };
  optional_block("tau", trajectory.tau);
  optional_block("ref", trajectory.ref);
  optional_block("qd", trajectory.qd);
  optional_block("qdd", trajectory.qdd);

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

}  // namespace

DatasetUpload dataset_from_json(const nlohmann::json& body) {
  Members members = members_from_json(body);
  return dataset_from_members(members);
}

DatasetUpload dataset_from_json_text(std::string_view text) {
  DatasetReader reader;
  fields::Json::sax_parse(text, &reader);
  return dataset_from_members(reader.members());
}

DatasetUpload dataset_from_csv(std::string_view text, const LogFormat& format) {
  DatasetUpload upload;
  upload.trajectory = trajectory_from_csv(format.empty() ? parse_csv(text) : apply_log_format(parse_csv(text), format));
  return upload;
}

DatasetUpload dataset_from_bag(std::string_view bytes, const BagOptions& options) {
  DatasetUpload upload;
  upload.trajectory = trajectory_from_csv(read_joint_states({bytes}, options).table);
  return upload;
}

}  // namespace manipid::api

// requests_fields.cpp — the strict JSON field readers of json_fields.h: type, finiteness and
// range checks with messages that name the field, say what was expected and what was found.
#include "json_fields.h"

#include "manipid/api/problem.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <set>
#include <utility>

namespace manipid::api::fields {
namespace {

// Quoted strings are cut to this many bytes so a huge value cannot flood the message.
constexpr std::size_t max_quoted_length = 40;

/// The text cut at a character boundary, with "..." when something was cut.
std::string shortened(std::string_view text) {
  if (text.size() <= max_quoted_length) return std::string(text);
  std::size_t end = max_quoted_length;
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xC0) == 0x80) --end;
  return std::string(text.substr(0, end)) + "...";
}

/// Edit distance, for "did you mean" on unknown keys (keys are short, so O(nm) is nothing).
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substitution = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitution});
    }
    std::swap(previous, current);
  }
  return previous[b.size()];
}

std::string expected_type_message(const std::string& path, std::string_view expected, const Json& value) {
  return field_name(path) + " must be " + std::string(expected) + ", got " + describe(value);
}

[[noreturn]] void throw_type(const std::string& path, std::string_view expected, const Json& value) {
  throw InputError(field_name(path), expected_type_message(path, expected, value));
}

std::string range_text(long long lowest, long long highest) {
  return std::to_string(lowest) + ".." + std::to_string(highest);
}

}  // namespace

// ---- Parsing ------------------------------------------------------------------------------

namespace {

/// Input quoted in a parse error: its last `most` characters (where the parser stopped).
std::string quoted_tail(std::string_view text, std::size_t most = 20) {
  if (text.size() <= most) return "'" + std::string(text) + "'";
  std::size_t start = text.size() - most;
  while (start < text.size() && (static_cast<unsigned char>(text[start]) & 0xC0) == 0x80) ++start;
  return "'..." + std::string(text.substr(start)) + "'";
}

/// Where the parser is, as a field path, while parsing: one frame per open object or array.
class ParsePosition {
 public:
  /// The path of the value being read now ("initial.m1", "q[0][3]"; "" at the top level).
  std::string current() const {
    if (frames_.empty()) return "";
    const Frame& frame = frames_.back();
    return frame.object ? member_path(frame.path, frame.key) : element_path(frame.path, frame.index);
  }

  /// nlohmann's parser callback: follows the structure and refuses a key seen twice in one object.
  bool on_event(Json::parse_event_t event, const Json& parsed) {
    switch (event) {
      case Json::parse_event_t::object_start:
      case Json::parse_event_t::array_start: {
        std::string path = current();
        frames_.push_back(Frame{event == Json::parse_event_t::object_start, std::move(path), {}, {}, 0});
        break;
      }
      case Json::parse_event_t::key: {
        Frame& frame = frames_.back();
        const std::string& key = parsed.get_ref<const std::string&>();
        if (!frame.keys.insert(key).second) throw_duplicate_key(frame.path, key);
        frame.key = key;
        break;
      }
      case Json::parse_event_t::object_end:
      case Json::parse_event_t::array_end:
        frames_.pop_back();
        if (!frames_.empty() && !frames_.back().object) ++frames_.back().index;
        break;
      case Json::parse_event_t::value:
        if (!frames_.empty() && !frames_.back().object) ++frames_.back().index;
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool object;
    std::string path;
    std::set<std::string> keys;  ///< an object's keys so far
    std::string key;             ///< an object's current key
    std::size_t index;           ///< an array's current element
  };
  std::vector<Frame> frames_;
};

/// nlohmann's "parse error at line 1, column 5: syntax error while parsing value - invalid
/// literal; last read: '<token>'" without its "[json.exception...]" prefix, the token cut short.
std::string syntax_error_text(const Json::parse_error& error) {
  std::string message = error.what();
  if (const auto start = message.find("parse error"); start != std::string::npos) message = message.substr(start);
  const std::string marker = "last read: '";
  if (const auto quote = message.find(marker); quote != std::string::npos) {
    const std::size_t token = quote + marker.size();
    const std::size_t end = message.rfind('\'');
    const std::string_view read = end > token ? std::string_view(message).substr(token, end - token) : std::string_view();
    message = message.substr(0, quote) + "last read: " + quoted_tail(read) + (end > token ? message.substr(end + 1) : "");
  }
  return message;
}

}  // namespace

void throw_duplicate_key(const std::string& object_path, const std::string& key) {
  const std::string field = member_path(object_path, shortened(key));
  throw InputError(field, "the key \"" + shortened(key) + "\" appears twice in " +
                              (object_path.empty() ? std::string("the body") : object_path) + "; send each key once");
}

void throw_parse_failure(const nlohmann::detail::exception& error, const std::string& where) {
  if (const auto* syntax = dynamic_cast<const Json::parse_error*>(&error)) {
    throw ApiError(ProblemKind::malformed_body, "the body is not valid JSON: " + syntax_error_text(*syntax), "body");
  }
  // 406 "number overflow parsing '<token>'": the only other error the parser reports.
  throw ApiError(ProblemKind::malformed_body,
                 "the body is not valid JSON for this server: a number " + std::string(where.empty() ? "" : "at " + where + " ") +
                     "is out of range (beyond about 1.8e308)",
                 "body");
}

Json parse_request(const std::string& text) {
  ParsePosition position;
  try {
    return Json::parse(text, [&position](int, Json::parse_event_t event, Json& parsed) {
      return position.on_event(event, parsed);
    });
  } catch (const Json::parse_error& error) {
    throw_parse_failure(error, position.current());
  } catch (const Json::out_of_range& error) {
    throw_parse_failure(error, position.current());
  }
}

std::string member_path(const std::string& parent, std::string_view key) {
  if (parent.empty()) return std::string(key);
  std::string path = parent;
  path += '.';
  path += key;
  return path;
}

std::string element_path(const std::string& parent, std::size_t index) {
  std::string path = parent;
  path += '[';
  path += std::to_string(index);
  path += ']';
  return path;
}

std::string field_name(const std::string& path) { return path.empty() ? "body" : path; }

std::string format_number(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string describe(const Json& value) {
  switch (value.type()) {
    case Json::value_t::null: return "null";
    case Json::value_t::boolean: return std::string("a boolean (") + (value.get<bool>() ? "true" : "false") + ")";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned: return "a number (" + value.dump() + ")";
    case Json::value_t::number_float: return "a number (" + format_number(value.get<double>()) + ")";
    case Json::value_t::string: return "a string (\"" + shortened(value.get_ref<const std::string&>()) + "\")";
    case Json::value_t::array: {
      const std::size_t size = value.size();
      return size == 0 ? "an empty array" : "an array of " + std::to_string(size) + (size == 1 ? " entry" : " entries");
    }
    case Json::value_t::object: return "an object";
    default: return "a binary value";
  }
}

std::size_t character_count(std::string_view text) {
  return static_cast<std::size_t>(
      std::count_if(text.begin(), text.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

// ---- Objects -----------------------------------------------------------------------------

void require_object(const Json& value, const std::string& path) {
  if (!value.is_object()) throw_type(path, "a JSON object", value);
}

ObjectFields::ObjectFields(const Json& value, std::string path, std::initializer_list<std::string_view> accepted)
    : object_(value), path_(std::move(path)) {
  require_object(value, path_);
  for (const auto& member : value.items()) {
    const std::string& key = member.key();
    if (std::find(accepted.begin(), accepted.end(), key) != accepted.end()) continue;
    std::string message = "unknown field \"" + shortened(key) + "\"";
    if (!path_.empty()) message += " in " + path_;
    // A near miss is almost always a typo of an accepted name: say which.
    std::string_view closest;
    std::size_t closest_distance = 3;
    for (std::string_view name : accepted) {
      // The distance is at least the length difference: skip names that cannot be within 2
      // (and a megabyte key costs nothing).
      if (key.size() > name.size() + 2 || name.size() > key.size() + 2) continue;
      const std::size_t distance = edit_distance(key, name);
      if (distance < closest_distance) {
        closest = name;
        closest_distance = distance;
      }
    }
    if (!closest.empty()) message += " (did you mean \"" + std::string(closest) + "\"?)";
    message += "; accepted fields: ";
    bool first = true;
    for (std::string_view name : accepted) {
      if (!first) message += ", ";
      message += name;
      first = false;
    }
    throw InputError(member_path(path_, shortened(key)), message);
  }
}

const Json* ObjectFields::find(std::string_view key) const {
  const auto found = object_.find(key);
  return found == object_.end() ? nullptr : &*found;
}

// ---- Scalars -----------------------------------------------------------------------------

double read_number(const Json& value, const std::string& path) {
  if (!value.is_number()) throw_type(path, "a number", value);
  const double number = value.get<double>();
  // JSON text cannot hold NaN or Inf, but a json built in code (or a huge literal) can.
  if (!std::isfinite(number)) {
    throw InputError(field_name(path), field_name(path) + " must be a finite number, got " + format_number(number));
  }
  return number;
}

double read_positive(const Json& value, const std::string& path, double maximum, std::string_view unit) {
  const double number = read_number(value, path);
  if (number > 0.0 && number <= maximum) return number;
  std::string message = field_name(path) + " must be ";
  if (std::isinf(maximum)) {
    message += "positive";
  } else {
    message += "in (0, " + format_number(maximum) + "]";
    message += unit;
  }
  throw InputError(field_name(path), message + ", got " + format_number(number));
}

double read_non_negative(const Json& value, const std::string& path) {
  const double number = read_number(value, path);
  if (number >= 0.0) return number;
  throw InputError(field_name(path), field_name(path) + " must not be negative, got " + format_number(number));
}

long long read_integer(const Json& value, const std::string& path, long long lowest, long long highest) {
  const std::string field = field_name(path);
  const std::string expected = "an integer in " + range_text(lowest, highest);
  if (value.is_number_unsigned()) {
    const auto number = value.get<std::uint64_t>();
    if (highest >= 0 && number <= static_cast<std::uint64_t>(highest) && static_cast<long long>(number) >= lowest) {
      return static_cast<long long>(number);
    }
    throw InputError(field, field + " must be " + expected + ", got " + value.dump());
  }
  if (value.is_number_integer()) {
    const auto number = value.get<long long>();
    if (number >= lowest && number <= highest) return number;
    throw InputError(field, field + " must be " + expected + ", got " + value.dump());
  }
  if (value.is_number_float()) {
    const double number = value.get<double>();
    if (std::isfinite(number) && number == std::floor(number) && number >= static_cast<double>(lowest) &&
        number <= static_cast<double>(highest)) {
      return static_cast<long long>(number);
    }
    throw InputError(field, field + " must be " + expected + ", got " + format_number(number));
  }
  throw_type(path, expected, value);
}

std::uint64_t read_unsigned(const Json& value, const std::string& path) {
  const std::string field = field_name(path);
  const std::string expected = "an integer in 0..18446744073709551615";
  if (value.is_number_unsigned()) return value.get<std::uint64_t>();
  if (value.is_number_integer()) {  // signed storage: parsed negatives, or built from a C++ int
    const auto number = value.get<long long>();
    if (number >= 0) return static_cast<std::uint64_t>(number);
    throw InputError(field, field + " must be " + expected + ", got " + value.dump());
  }
  if (value.is_number_float()) {
    const double number = value.get<double>();
    // 2^64 is exactly representable; anything at or above it does not fit.
    if (std::isfinite(number) && number == std::floor(number) && number >= 0.0 && number < 18446744073709551616.0) {
      return static_cast<std::uint64_t>(number);
    }
    throw InputError(field, field + " must be " + expected + ", got " + format_number(number));
  }
  throw_type(path, expected, value);
}

std::string read_string(const Json& value, const std::string& path) {
  if (!value.is_string()) throw_type(path, "a string", value);
  // Every string field is a name; a bounded one keeps a megabyte "preset" out of the
  // messages that quote it.
  constexpr std::size_t max_bytes = 256;
  if (value.get_ref<const std::string&>().size() > max_bytes) {
    throw InputError(field_name(path), field_name(path) + " is " + std::to_string(value.get_ref<const std::string&>().size()) +
                                           " bytes long, at most " + std::to_string(max_bytes) + " are allowed");
  }
  return value.get<std::string>();
}

std::string read_label(const Json& value, const std::string& path, std::size_t max_characters) {
  if (!value.is_string()) throw_type(path, "a string", value);
  std::string text = value.get<std::string>();
  const std::size_t characters = character_count(text);
  if (characters > max_characters) {
    throw InputError(field_name(path), field_name(path) + " has " + std::to_string(characters) +
                                           " characters, at most " + std::to_string(max_characters) +
                                           " are allowed");
  }
  return text;
}

std::string read_choice(const Json& value, const std::string& path, std::initializer_list<std::string_view> choices) {
  std::string expected = "one of ";
  bool first = true;
  for (std::string_view choice : choices) {
    if (!first) expected += ", ";
    expected += "\"" + std::string(choice) + "\"";
    first = false;
  }
  if (!value.is_string()) throw_type(path, expected, value);
  const std::string& text = value.get_ref<const std::string&>();
  if (std::find(choices.begin(), choices.end(), text) == choices.end()) {
    throw InputError(field_name(path), field_name(path) + " must be " + expected + ", got \"" + shortened(text) + "\"");
  }
  return text;
}

// ---- Arrays and parameter objects ----------------------------------------------------------

std::vector<double> read_joint_numbers(const Json& value, const std::string& path, int joints, bool positive) {
  if (!value.is_array()) throw_type(path, "an array of " + std::to_string(joints) + " numbers, one per joint", value);
  if (value.size() != static_cast<std::size_t>(joints)) {
    throw InputError(field_name(path), field_name(path) + " has " + std::to_string(value.size()) +
                                           " entries, expected " + std::to_string(joints) + " (one per joint)");
  }
  std::vector<double> numbers;
  numbers.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string element = element_path(path, i);
    numbers.push_back(positive ? read_positive(value[i], element) : read_number(value[i], element));
  }
  return numbers;
}

Eigen::VectorXd read_gains(const Json& value, const std::string& path, int joints) {
  const std::vector<double> numbers = read_joint_numbers(value, path, joints, true);
  return Eigen::Map<const Eigen::VectorXd>(numbers.data(), static_cast<Eigen::Index>(numbers.size()));
}

void read_parameter_object(const Json& value, const std::string& path, int joints, bool non_negative,
                           const std::function<void(int index, double number, const std::string& field)>& apply) {
  require_object(value, path);
  const std::string last = std::to_string(joints);
  for (const auto& member : value.items()) {
    const std::string& name = member.key();
    const std::string field = member_path(path, name);
    const int index = parameter_index(name, joints);
    if (index < 0) {
      throw InputError(field, "unknown parameter \"" + shortened(name) + "\" in " + path + " (this robot has m1..m" +
                                  last + " and l1..l" + last + ")");
    }
    const double number = non_negative ? read_non_negative(member.value(), field) : read_number(member.value(), field);
    apply(index, number, field);
  }
}

void rethrow_at(const InputError& error, const std::string& path) {
  throw InputError(field_name(path), error.what());
}

}  // namespace manipid::api::fields

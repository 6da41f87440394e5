// json_fields.h — internal to api/: strict readers of JSON request fields, shared by the
// dataset, simulation and identification codecs (requests_*.cpp).
//
// Every reader takes the value and its path in the body ("q[2]", "simulation.noise.seed") and
// throws InputError(path, message) on a wrong JSON type, a non-finite number or a value out
// of range; messages say what was expected and what was found. Paths index arrays from 0, as
// JSON does.
#pragma once

#include "manipid/api/limits.h"
#include "manipid/api/requests.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace manipid::api::fields {

using Json = nlohmann::json;

inline constexpr double infinity = std::numeric_limits<double>::infinity();
/// Longest label (dataset and simulation "name"), in characters.
inline constexpr std::size_t max_name_characters = 200;
/// Most samples a dataset or simulation may have (limits.h owns it), as a double for range checks.
inline constexpr double max_samples = static_cast<double>(limits::max_samples);

/// "simulation" + "noise" → "simulation.noise"; "" + "q" → "q".
std::string member_path(const std::string& parent, std::string_view key);
/// "q" + 2 → "q[2]".
std::string element_path(const std::string& parent, std::size_t index);
/// The path as an error field: the whole body is "body".
std::string field_name(const std::string& path);
/// What a value is, for messages: `a string ("abc")`, `a number (2.5)`, `an array of 3 entries`.
std::string describe(const Json& value);
/// Shortest text that reads back to the same double ("0.1", "1e-08", "inf").
std::string format_number(double value);
/// Characters (UTF-8 code points) in a string.
std::size_t character_count(std::string_view text);

/// A request body parsed as JSON, refusing what nlohmann would take silently: a key twice in
/// one object (nlohmann keeps the last) is InputError naming the key's path. Text that is not
/// JSON, and numbers beyond a double (1e400), are ApiError malformed_body (field "body") saying
/// where, in words, quoting at most 20 characters of the input.
Json parse_request(const std::string& text);
/// The refusal of a key seen twice in the object at `object_path` ("" for the body).
[[noreturn]] void throw_duplicate_key(const std::string& object_path, const std::string& key);
/// A parser failure as parse_request answers it: a syntax error, or a number beyond a double
/// at `where` (the path of the value being read).
[[noreturn]] void throw_parse_failure(const nlohmann::detail::exception& error, const std::string& where);

/// A JSON object read member by member. The constructor checks that the value is an object
/// and that every key is accepted, so a typo ("max_evaluation") is an error, never ignored.
class ObjectFields {
 public:
  ObjectFields(const Json& value, std::string path, std::initializer_list<std::string_view> accepted);

  /// The member, or nullptr when absent.
  const Json* find(std::string_view key) const;
  bool has(std::string_view key) const { return find(key) != nullptr; }
  /// The member's path in the body.
  std::string path(std::string_view key) const { return member_path(path_, key); }
  const std::string& path() const { return path_; }
  const Json& value() const { return object_; }

 private:
  const Json& object_;
  std::string path_;
};

/// Throws unless the value is an object.
void require_object(const Json& value, const std::string& path);

/// A finite number.
double read_number(const Json& value, const std::string& path);
/// A finite number in (0, maximum]; `unit` is appended to the range in messages (" s").
double read_positive(const Json& value, const std::string& path, double maximum = infinity,
                     std::string_view unit = "");
/// A finite number ≥ 0.
double read_non_negative(const Json& value, const std::string& path);
/// A whole number in lowest..highest. Integral floats (1e4, 100.0) are accepted: many JSON
/// writers (MATLAB, JavaScript) do not distinguish them from integers.
long long read_integer(const Json& value, const std::string& path, long long lowest, long long highest);
/// A whole number in 0..2^64-1.
std::uint64_t read_unsigned(const Json& value, const std::string& path);
/// A name (preset, method, parameter, id): a string of at most 256 bytes.
std::string read_string(const Json& value, const std::string& path);
/// A string of at most `max_characters` characters (a label).
std::string read_label(const Json& value, const std::string& path, std::size_t max_characters = max_name_characters);
/// One of `choices`, exactly.
std::string read_choice(const Json& value, const std::string& path, std::initializer_list<std::string_view> choices);

/// An array of exactly `joints` finite numbers, one per joint; with `positive` each must be > 0.
std::vector<double> read_joint_numbers(const Json& value, const std::string& path, int joints, bool positive);
/// Controller gains: `joints` positive numbers.
Eigen::VectorXd read_gains(const Json& value, const std::string& path, int joints);

/// An object of parameter values by name ({"m2": 24, "l3": 0.6}). Each name must be one of
/// m1..mn, l1..ln and each value a finite number (≥ 0 with `non_negative`); `apply` receives
/// the θ index, the value and the member's path.
void read_parameter_object(const Json& value, const std::string& path, int joints, bool non_negative,
                           const std::function<void(int index, double number, const std::string& field)>& apply);

/// Rethrows a core InputError for a setting at `path` (the core names only the last part).
[[noreturn]] void rethrow_at(const InputError& error, const std::string& path);

// ---- Shared by simulations and identifications ---------------------------------------------

/// simulation_from_json with every field path under `path` ("" at the top, "simulation" when
/// nested in an identification request).
SimulationSpec read_simulation(const Json& body, const std::string& path);
/// Samples the simulation produces: round(duration / dt) + 1, as simulate_closed_loop does.
int simulation_samples(const SimulationSpec& spec);

}  // namespace manipid::api::fields

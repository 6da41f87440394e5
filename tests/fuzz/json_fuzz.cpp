// json_fuzz.cpp — libFuzzer target for the JSON request parsers of api/requests.h:
// fields::parse_request (the server's JSON parse: duplicate keys, number overflow), then
// dataset_from_json, simulation_from_json and identification_from_json (and the data checks of
// check_against_data). Every input must end in a value or a clean InputError / ApiError; any
// other exception escapes (libFuzzer reports it as a crash), as do ASan/UBSan findings.
//
// Each JSON object goes to all three parsers: each rejects a foreign object at its first
// unknown key, which costs far less than the JSON parse, so one input explores all three
// without the fuzzer having to learn a selector byte. run_simulation is never called.
// A dataset that parses is also written as CSV and read back, which must give it unchanged.
#include "manipid/api/csv.h"
#include "manipid/api/problem.h"
#include "manipid/api/requests.h"
#include "manipid/core/errors.h"

#include "json_fields.h"  // api/src: fields::parse_request

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

using manipid::InputError;
using manipid::api::ApiError;

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "json_fuzz: %s\n", what);
  std::abort();
}

/// Runs one parser; only the two documented exception types count as a clean rejection.
template <class Parse>
void clean(Parse parse) {
  try {
    parse();
  } catch (const InputError&) {
  } catch (const ApiError&) {
  }
}

/// A dataset written as CSV must read back to exactly the same trajectory.
void check_csv_round_trip(const manipid::Trajectory& trajectory) {
  manipid::Trajectory back;
  try {
    const std::string text = manipid::api::format_csv(manipid::api::trajectory_to_csv(trajectory));
    back = manipid::api::dataset_from_csv(text).trajectory;
  } catch (const InputError& error) {
    std::fprintf(stderr, "json_fuzz: %s\n", error.what());
    fail("a valid dataset's CSV form was rejected");
  }
  if (back.t != trajectory.t || back.q != trajectory.q) fail("CSV round trip changed t or q");
  if (back.tau.cols() != trajectory.tau.cols() || (trajectory.has_torque() && back.tau != trajectory.tau)) {
    fail("CSV round trip changed tau");
  }
  if (back.ref.cols() != trajectory.ref.cols() || (trajectory.has_reference() && back.ref != trajectory.ref)) {
    fail("CSV round trip changed ref");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The server's one JSON parse (fields::parse_request): syntax errors, numbers beyond a double
  // and duplicate keys are clean rejections, anything else escapes.
  const std::string text(reinterpret_cast<const char*>(data), size);
  // The upload route's reader (SAX, no document): the same clean rejections.
  clean([&] { (void)manipid::api::dataset_from_json_text(text); });
  nlohmann::json body;
  clean([&] { body = manipid::api::fields::parse_request(text); });
  if (!body.is_object()) return 0;  // rejected or not an object: no parser takes it

  clean([&] {
    const manipid::api::DatasetUpload upload = manipid::api::dataset_from_json(body);
    check_csv_round_trip(upload.trajectory);
  });
  clean([&] { (void)manipid::api::simulation_from_json(body); });
  clean([&] {
    const manipid::api::IdentificationSpec spec = manipid::api::identification_from_json(body);
    if (spec.simulation) return;  // identification_from_json already checked it against its data
    // Stand-in data whose shape comes from the input's length, so the fuzzer reaches every
    // check: 3 or 4 joints, `size` samples, with or without tau and ref columns.
    const int joints = size % 5 == 0 ? 3 : 4;
    manipid::api::check_against_data(spec, joints, static_cast<int>(size), (size & 1) != 0, (size & 2) != 0);
  });
  return 0;
}

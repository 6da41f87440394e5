// submissions.cpp — what starts jobs: the robot presets a request starts from (/v1/presets),
// and the two submissions, /v1/simulations and /v1/identifications, validated in full before
// anything is queued.
#include "manipid/api/problem.h"
#include "manipid/api/requests.h"
#include "manipid/api/resources_json.h"
#include "manipid/api/robot_requests.h"

#include "http/request_helpers.h"  // includes httplib.h, after the manipid headers
#include "http/responses.h"
#include "routes/handlers.h"

#include <cmath>

namespace manipid::api::http {
namespace {

void submit(RouteState& state, const httplib::Request& request, httplib::Response& response, JobKind kind) {
  const Caller caller = caller_of(state, request);
  const auto key = idempotency_key(request);
  const nlohmann::json body = json_body(request);
  std::string dataset_id;
  if (kind == JobKind::simulation) {
    (void)simulation_from_json(body);  // validates; the worker parses the stored text again
  } else {
    const IdentificationSpec spec = identification_from_json(body);
    if (spec.simulation) {
      const SimulationOptions& run = spec.simulation->preset.simulation;
      const int samples = static_cast<int>(std::floor(run.duration / run.dt + 1e-9)) + 1;
      check_against_data(spec, spec.simulation->preset.model.joint_count(), samples, true, true);
    } else {
      dataset_id = spec.dataset_id;
      const auto dataset = state.service.dataset(caller, dataset_id);
      if (!dataset) throw ApiError(ProblemKind::invalid_field, "no dataset " + dataset_id, "dataset_id");
      check_against_data(spec, dataset->joints, dataset->samples, dataset->has_torque, dataset->has_reference);
    }
  }
  const SubmitResult submitted = state.service.submit(caller, {kind, body.dump(), dataset_id, "", ""}, key);
  response.set_header("Location", "/v1/jobs/" + submitted.job.id);
  if (submitted.replayed) response.set_header("Idempotent-Replayed", "true");
  send_job(response, 202, submitted.job);
}

}  // namespace

void submit_simulation(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  submit(state, request, response, JobKind::simulation);
}

void submit_identification(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  const Caller caller = caller_of(state, request);
  const auto key = idempotency_key(request);
  const nlohmann::json body = json_body(request);
  if (names_a_robot(body)) {
    submit_robot_identification(state, caller, body, key, response);
    return;
  }
  submit(state, request, response, JobKind::identification);
}

void list_presets(RouteState&, const httplib::Request&, httplib::Response& response) {
  nlohmann::ordered_json items = nlohmann::ordered_json::array();
  for (const std::string& name : preset_names()) items.push_back(preset_to_json(find_preset(name)));
  send_json(response, 200, {{"items", items}});
}

void get_preset(RouteState&, const httplib::Request& request, httplib::Response& response) {
  const std::string name = request.matches[1];
  const KineticEnergy energy = request.has_param("kinetic_energy")
                                   ? parse_kinetic_energy(request.get_param_value("kinetic_energy"), "kinetic_energy")
                                   : KineticEnergy::complete;
  const Preset preset = [&] {
    try {
      return find_preset(name, energy);
    } catch (const InputError& error) {  // an unknown name: it lists the known ones
      throw ApiError(ProblemKind::not_found, error.what(), "name");
    }
  }();
  send_json(response, 200, preset_to_json(preset));
}

}  // namespace manipid::api::http

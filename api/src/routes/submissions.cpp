// submissions.cpp — what starts jobs: the robot presets a request starts from (/v1/presets), and every
// submission (/v1/simulations, /v1/identifications, /v1/excitations), validated in full by its kind's entry of
// job_kinds.h before anything is queued.
#include "manipid/api/job_kinds.h"
#include "manipid/api/problem.h"
#include "manipid/api/requests.h"
#include "manipid/api/resources_json.h"
#include "manipid/api/robot_requests.h"

#include "http/request_helpers.h"  // includes httplib.h, after the manipid headers
#include "http/responses.h"
#include "routes/handlers.h"


namespace manipid::api::http {

void submit_job(RouteState& state, const httplib::Request& request, httplib::Response& response,
                const std::function<JobKind(const nlohmann::json& body)>& kind_of) {
  const Caller caller = caller_of(state, request);
  const auto key = idempotency_key(request);
  const nlohmann::json body = json_body(request);
  const SubmissionLookups lookups{
      [&](const std::string& id) { return state.service.dataset(caller, id); },
      [&](const std::string& id, const std::string& field) { return stored_robot(state, caller, id, field); },
      [&](const std::string& id) { return state.service.job(caller, id); }};
  const JobSubmission submission = job_kind_handler(kind_of(body)).submission(body, lookups);
  const SubmitResult submitted = state.service.submit(caller, submission, key);
  response.set_header("Location", "/v1/jobs/" + submitted.job.id);
  if (submitted.replayed) response.set_header("Idempotent-Replayed", "true");
  send_job(response, 202, submitted.job);
}

void submit_simulation(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  submit_job(state, request, response, [](const nlohmann::json&) { return JobKind::simulation; });
}

void submit_identification(RouteState& state, const httplib::Request& request, httplib::Response& response) {
  submit_job(state, request, response, identification_kind);  // the preset's, a stored robot's, or a payload's
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

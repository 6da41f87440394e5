// job_runner.cpp — one job from its stored request to its outcome (job_runner.h).
#include "jobs/job_runner.h"

#include "manipid/api/job_kinds.h"
#include "manipid/api/limits.h"
#include "manipid/api/payload_json.h"
#include "manipid/api/problem.h"
#include "manipid/api/requests.h"
#include "manipid/api/result_json.h"
#include "manipid/api/robot_identification_run.h"
#include "manipid/api/robot_json.h"
#include "manipid/api/robot_requests.h"
#include "manipid/api/robot_result.h"
#include "manipid/core/robot/excitation.h"
#include "manipid/core/robot/identification.h"
#include "manipid/core/robot/payload.h"
#include "manipid/core/paper/identification.h"
#include "manipid/core/paper/simulation.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <new>
#include <sstream>
#include <thread>

namespace manipid::server::jobs {

void heed(store::LeaseStatus status, LiveJob& live) {
  if (status == store::LeaseStatus::lost) {
    live.lost = true;
    live.cancel = true;
  } else if (status == store::LeaseStatus::cancel_requested) {
    live.cancel = true;
  }
}

namespace {

using Clock = std::chrono::steady_clock;

std::string job_failed(const std::string& detail) {
  // A computation that could not finish (a diverging simulation, a store failure): the
  // request was valid, so this is not one of the request's problem kinds.
  return api::problem_to_json({api::ProblemKind::job_failed, detail, ""}).dump();
}

JobOutcome failed(std::string error) {
  JobOutcome outcome;
  outcome.state = api::JobState::failed;
  outcome.error = std::move(error);
  return outcome;
}

/// The job's clock: when it started and how long --job-timeout lets it run.
struct JobClock {
  Clock::time_point started = Clock::now();
  double limit_seconds = 3600.0;

  double elapsed() const { return std::chrono::duration<double>(Clock::now() - started).count(); }
  bool expired() const { return elapsed() >= limit_seconds; }
};

/// How long past --job-timeout a job that does not stop by itself at the limit may go on before its cancel
/// flag is set (kinds that stop at the limit themselves — an identification's max_seconds, a simulation's
/// should_stop — end first, with their own outcome).
constexpr double kTimeLimitGrace = 0.5;

/// Sets a job's cancel flag (and timed_out) once its time limit and kTimeLimitGrace have passed. Every job
/// kind checks that flag inside its long steps, so the limit holds also where a kind has no clock of its
/// own (a URDF robot's identification) or one step outlasts it (a many-joint excitation's evaluation).
class TimeLimit {
 public:
  TimeLimit(LiveJob& live, double seconds)
      : thread_([this, &live, seconds] {
          const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                   std::chrono::duration<double>(std::min(seconds + kTimeLimitGrace, 1e9)));
          std::unique_lock lock(mutex_);
          if (ended_.wait_until(lock, deadline, [this] { return done_; })) return;
          if (!live.cancel.load()) {
            live.timed_out = true;
            live.cancel = true;
          }
        }) {}
  ~TimeLimit() {
    {
      std::lock_guard lock(mutex_);
      done_ = true;
    }
    ended_.notify_all();
    thread_.join();
  }
  TimeLimit(const TimeLimit&) = delete;
  TimeLimit& operator=(const TimeLimit&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable ended_;
  bool done_ = false;
  std::thread thread_;  // last: started once the members it waits on exist
};

/// A job stopped by its TimeLimit: failed, saying which limit and while doing what.
JobOutcome timed_out(const JobClock& clock, const char* doing) {
  std::ostringstream detail;
  detail << "the job reached its time limit (--job-timeout " << clock.limit_seconds << " s) while " << doing;
  return failed(job_failed(detail.str()));
}

/// A simulation stopped by its should_stop, ended the way an identification's stop is: a shutdown's
/// cancel requeues the job, a user's cancel cancels it, and otherwise the time limit ran out.
JobOutcome stopped_simulation(const LiveJob& live, const JobClock& clock, const SimulationStopped& stopped) {
  JobOutcome outcome;
  if (live.cancel.load() && !live.timed_out.load()) {
    outcome.requeue = live.shutdown.load();
    outcome.state = api::JobState::cancelled;
    return outcome;
  }
  std::ostringstream detail;
  detail << "the job reached its time limit (--job-timeout " << clock.limit_seconds << " s) while simulating, at t = "
         << stopped.time() << " s of simulated time";
  return failed(job_failed(detail.str()));
}

/// The dataset a simulation makes, stored idempotently under the job's id so a job re-run
/// after a crash finds the dataset its first run stored instead of making a second one. The
/// integration stops (SimulationStopped) when the job is cancelled or its time is up.
api::DatasetInfo store_simulated(store::Store& store, const api::JobInfo& job, api::SimulationSpec spec,
                                 const LiveJob& live, const JobClock& clock) {
  spec.preset.simulation.should_stop = [&live, &clock] { return live.cancel.load(std::memory_order_relaxed) || clock.expired(); };
  const Trajectory data = api::run_simulation(spec);
  const api::IdempotencyKey key{"job-output:" + job.id, job.id};
  const std::string name = spec.name.empty() ? "simulation " + spec.preset.name + " (" + job.id + ")" : spec.name;
  return store.insert_dataset(job.owner, name, data, job.id, key).dataset;
}

JobOutcome run_simulation_job(const api::JobInfo& job, store::Store& store, const LiveJob& live, const JobClock& clock) {
  const auto started = Clock::now();
  const api::SimulationSpec spec = api::simulation_from_json(nlohmann::json::parse(job.request));
  const api::DatasetInfo dataset = store_simulated(store, job, spec, live, clock);
  JobOutcome outcome;
  outcome.state = api::JobState::succeeded;
  outcome.dataset_id = dataset.id;
  outcome.result = nlohmann::ordered_json{
      {"dataset_id", dataset.id},
      {"joints", dataset.joints},
      {"samples", dataset.samples},
      {"dt", dataset.dt},
      {"has_torque", dataset.has_torque},
      {"has_reference", dataset.has_reference},
      {"wall_seconds", std::chrono::duration<double>(Clock::now() - started).count()},
  }.dump();
  return outcome;
}

/// Collects every evaluation and writes them to the store in batches.
class HistoryWriter {
 public:
  HistoryWriter(store::Store& store, LiveJob& live, const RunnerOptions& options)
      : store_(store), live_(live), options_(options), last_flush_(Clock::now()) {}

  void add(long index, double cost, const Eigen::VectorXd& theta) {
    batch_.push_back({index, cost, std::vector<double>(theta.data(), theta.data() + theta.size())});
    live_.evaluations.store(index + 1, std::memory_order_relaxed);
    if (std::isfinite(cost) && cost < live_.best_cost.load(std::memory_order_relaxed)) {
      live_.best_cost.store(cost, std::memory_order_relaxed);
    }
    if (static_cast<int>(batch_.size()) >= options_.history_batch ||
        std::chrono::duration<double>(Clock::now() - last_flush_).count() >= options_.history_flush_seconds) {
      flush();
    }
  }

  /// The entries not yet written go with the job's end (one transaction with the result), with
  /// the progress counters.
  void hand_over(store::JobEnd& end) {
    end.history = std::move(batch_);
    batch_.clear();
    end.evaluations = live_.evaluations.load(std::memory_order_relaxed);
    end.best_cost = best_cost();
  }

  void flush() {
    if (live_.lost.load()) return;
    try {
      heed(store_.record_progress(live_.lease, live_.evaluations.load(std::memory_order_relaxed), best_cost(), batch_),
           live_);
    } catch (const store::StoreUnavailable&) {
      // The database is away for a moment (a PostgreSQL restart): the batch waits for the next
      // flush. Should the outage outlast the lease, another process takes the job over and this
      // attempt's next write learns it lost the lease.
      last_flush_ = Clock::now();
      return;
    }
    batch_.clear();
    last_flush_ = Clock::now();
  }

 private:
  /// The lowest cost so far; none while every cost was non-finite.
  std::optional<double> best_cost() const {
    const double best = live_.best_cost.load(std::memory_order_relaxed);
    return std::isfinite(best) ? std::optional<double>(best) : std::nullopt;
  }

  store::Store& store_;
  LiveJob& live_;
  const RunnerOptions& options_;
  std::vector<api::HistoryEntry> batch_;
  Clock::time_point last_flush_;
};

/// The simulation that made a stored dataset (a simulation job's, or an identification's that
/// simulated first), if one did.
std::optional<api::SimulationSpec> simulation_behind(store::Store& store, const std::string& dataset_id) {
  const auto dataset = store.find_dataset(api::all_owners, dataset_id);
  if (!dataset || dataset->source_job.empty()) return std::nullopt;
  const auto source = store.find_job(api::all_owners, dataset->source_job);
  if (!source) return std::nullopt;
  try {
    if (source->kind == api::JobKind::simulation) return api::simulation_from_json(nlohmann::json::parse(source->request));
    if (source->kind == api::JobKind::identification) {
      return api::identification_from_json(nlohmann::json::parse(source->request)).simulation;
    }
  } catch (const std::exception&) {
    // A request stored by an older version that no longer parses: no truth, not a failed job.
  }
  return std::nullopt;
}

/// What the result shows as true values (api::known_truth): never a preset's for uploaded data.
Eigen::VectorXd truth_of(store::Store& store, const api::IdentificationSpec& spec, const std::string& dataset_id) {
  if (spec.truth.size() > 0 || spec.simulation) return api::known_truth(spec, nullptr);
  const std::optional<api::SimulationSpec> simulation = simulation_behind(store, dataset_id);
  return api::known_truth(spec, simulation ? &*simulation : nullptr);
}

JobOutcome run_identification_job(const api::JobInfo& job, store::Store& store, LiveJob& live, const RunnerOptions& options,
                                  const JobClock& clock) {
  api::IdentificationSpec spec = api::identification_from_json(nlohmann::json::parse(job.request));
  std::string dataset_id = spec.dataset_id;
  std::optional<Trajectory> data;
  if (spec.simulation) {
    dataset_id = store_simulated(store, job, *spec.simulation, live, clock).id;
  }
  data = store.load_dataset(api::all_owners, dataset_id);
  if (!data) {
    JobOutcome outcome = failed(api::problem_to_json({api::ProblemKind::not_found,
                                                      "dataset " + dataset_id + " was deleted before the job ran",
                                                      "dataset_id"})
                                    .dump());
    outcome.dataset_id = dataset_id;
    return outcome;
  }
  api::check_against_data(spec, data->joint_count(), data->samples(), data->has_torque(), data->has_reference());

  HistoryWriter history(store, live, options);
  IdentificationOptions& identification = spec.options;
  // The time limit is the whole job's: what a simulation first took is not given again.
  identification.max_seconds =
      std::min(identification.max_seconds, std::max(options.job_time_limit_seconds - clock.elapsed(), 1e-3));
  identification.cancel = &live.cancel;
  identification.on_evaluation = [&history](long index, double cost, const Eigen::VectorXd& theta) {
    history.add(index, cost, theta);
  };
  const IdentificationResult result = identify(spec.preset.model, *data, identification);

  JobOutcome outcome;
  outcome.dataset_id = dataset_id;
  if (result.cancelled && live.shutdown.load()) {
    outcome.requeue = true;
    return outcome;
  }
  history.hand_over(outcome);
  outcome.state = result.cancelled ? api::JobState::cancelled : api::JobState::succeeded;
  nlohmann::ordered_json json = api::result_to_json(result, truth_of(store, spec, dataset_id));
  json["dataset_id"] = dataset_id;
  outcome.result = json.dump();
  for (std::size_t i = 0; i < result.names.size(); ++i) {
    // Stored estimates are what the data determine, as in the result's "estimates".
    if (!result.free[i] || !result.identifiability.determines_alone(result.names[i])) continue;
    const double error = result.std_errors[static_cast<Eigen::Index>(i)];
    outcome.estimates.push_back({result.names[i], result.estimate[static_cast<Eigen::Index>(i)],
                                 std::isfinite(error) ? std::optional<double>(error) : std::nullopt});
  }
  return outcome;
}

/// A stored robot parsed (the process's RobotCache when the runner has one), or nullptr when it is gone.
std::shared_ptr<const api::ParsedRobot> stored_robot(store::Store& store, const RunnerOptions& options,
                                                     const std::optional<api::RobotInfo>& robot) {
  if (!robot) return nullptr;
  const auto load = [&] { return store.load_robot_urdf(api::all_owners, robot->id); };
  if (options.robots) return options.robots->get(*robot, load);
  const std::optional<std::string> urdf = load();
  if (!urdf) return nullptr;
  return std::make_shared<const api::ParsedRobot>(api::parse_robot({robot->name, *urdf, robot->base, robot->tip}));
}

/// A failed end for something a queued job names that was deleted before it ran.
JobOutcome deleted_before_run(const std::string& what, const std::string& field, const std::string& dataset_id) {
  JobOutcome outcome = failed(api::problem_to_json({api::ProblemKind::not_found, what + " was deleted before the job ran", field}).dump());
  outcome.dataset_id = dataset_id;
  return outcome;
}

/// What a job on a stored robot reads (api::RobotRuns): the robot parsed, its training and validation runs,
/// each checked against it; or the failed end when one of them was deleted before the job ran.
struct LoadedRobotRuns {
  std::shared_ptr<const api::ParsedRobot> robot;
  std::vector<Trajectory> runs, held_out;
  std::optional<JobOutcome> missing;
};

LoadedRobotRuns load_robot_runs(store::Store& store, const RunnerOptions& options, const api::RobotRuns& spec) {
  LoadedRobotRuns loaded;
  loaded.robot = stored_robot(store, options, store.find_robot(api::all_owners, spec.robot_id));
  if (!loaded.robot) {
    loaded.missing = deleted_before_run("robot " + spec.robot_id, "robot_id", spec.dataset_id);
    return loaded;
  }
  const robot::Model& model = loaded.robot->model;
  const auto load = [&](const std::vector<std::string>& ids, const std::string& field, std::vector<Trajectory>& runs) {
    for (std::size_t i = 0; i < ids.size() && !loaded.missing; ++i) {
      const std::string where = ids.size() > 1 ? field + "s[" + std::to_string(i) + "]" : field;
      auto data = store.load_dataset(api::all_owners, ids[i]);
      if (!data) {
        loaded.missing = deleted_before_run("dataset " + ids[i], where, spec.dataset_id);
        return;
      }
      api::check_robot_data(model.joint_count(), model.name, data->joint_count(), data->has_torque(), where);
      runs.push_back(std::move(*data));
    }
  };
  load(spec.dataset_ids, "dataset_id", loaded.runs);
  load(spec.validation_dataset_ids, "validation_dataset_id", loaded.held_out);
  return loaded;
}

/// The end of a job on a stored robot that its cancel flag stopped: put back in the queue at a shutdown,
/// else cancelled.
JobOutcome stopped_robot_job(const LiveJob& live, const std::string& dataset_id) {
  JobOutcome outcome;
  outcome.dataset_id = dataset_id;
  if (live.shutdown.load()) {
    outcome.requeue = true;
    return outcome;
  }
  outcome.state = api::JobState::cancelled;
  outcome.result = nlohmann::ordered_json{{"cancelled", true}, {"dataset_id", dataset_id}}.dump();
  return outcome;
}

/// The runs a job read, as its result names them.
void name_runs(nlohmann::ordered_json& json, const api::RobotRuns& spec) {
  json["robot_id"] = spec.robot_id;
  json["dataset_id"] = spec.dataset_id;
  json["dataset_ids"] = spec.dataset_ids;
  if (!spec.validation_dataset_ids.empty()) {
    json["validation_dataset_id"] = spec.validation_dataset_id;
    json["validation_dataset_ids"] = spec.validation_dataset_ids;
  }
}

/// A URDF robot's identification: one least-squares solve on its runs (the filters, ridge and friction terms
/// chosen by held-out prediction), judged on validation runs if asked. No evaluations to stream: the job's
/// progress is its state.
JobOutcome run_robot_identification_job(const api::JobInfo& job, store::Store& store, LiveJob& live,
                                        const RunnerOptions& options) {
  api::RobotIdentificationSpec spec = api::robot_identification_from_json(nlohmann::json::parse(job.request));
  LoadedRobotRuns loaded = load_robot_runs(store, options, spec);
  if (loaded.missing) return *loaded.missing;
  const api::ParsedRobot& parsed = *loaded.robot;

  spec.options.cancel = &live.cancel;
  const api::RobotIdentificationRun run = api::run_robot_identification(
      parsed.model, loaded.runs, spec.options, [&loaded] { return std::move(loaded.held_out); });
  const robot::IdentificationResult& result = run.result;
  if (result.cancelled) return stopped_robot_job(live, spec.dataset_id);
  nlohmann::ordered_json json = run.json;
  name_runs(json, spec);
  JobOutcome outcome;
  outcome.dataset_id = spec.dataset_id;
  outcome.state = api::JobState::succeeded;
  outcome.result = json.dump();
  for (int i = 0; i < result.base.size(); ++i) {
    const double error = result.std_errors[i];
    outcome.estimates.push_back({result.base.names[static_cast<std::size_t>(i)], result.estimate[i],
                                 std::isfinite(error) ? std::optional<double>(error) : std::nullopt});
  }
  return outcome;
}

/// A payload on a stored robot's tip link (robot/payload.h): the arm from arm_job_id's result (or the URDF's
/// values), one linear least-squares solve on the runs carrying the payload, the held-out runs predicted with
/// and without it. The result is payload_json.h's object with the runs and the arm it used ("arm_point"), so its
/// views stand when the arm's job is deleted.
JobOutcome run_payload_identification_job(const api::JobInfo& job, store::Store& store, LiveJob& live,
                                          const RunnerOptions& options) {
  api::PayloadIdentificationSpec spec = api::payload_identification_from_json(nlohmann::json::parse(job.request));
  LoadedRobotRuns loaded = load_robot_runs(store, options, spec);
  if (loaded.missing) return *loaded.missing;
  const robot::Model& model = loaded.robot->model;
  robot::ArmParameters arm = api::urdf_arm(model);
  std::string arm_source = "the URDF's values";
  if (!spec.arm_job_id.empty()) {
    const std::optional<api::JobInfo> arm_job = store.find_job(api::all_owners, spec.arm_job_id);
    if (!arm_job) return deleted_before_run("job " + spec.arm_job_id, "arm_job_id", spec.dataset_id);
    arm = api::arm_of_job(model, arm_job, spec.arm_job_id, spec.robot_id);
    arm_source = "identified (job " + spec.arm_job_id + ")";
  }

  spec.options.cancel = &live.cancel;
  // The core names the run's parts ("q", "tau", "validation") and the arm ("arm"): the request's fields say them.
  const auto in_request = [](const InputError& error, const std::string& runs_field) -> InputError {
    if (error.field() == "arm") return InputError("arm_job_id", error.what());
    if (error.field() == "q" || error.field() == "tau" || error.field() == "validation") return InputError(runs_field, error.what());
    return error;
  };
  robot::PayloadResult result;
  try {
    result = robot::identify_payload(model, arm, loaded.runs, spec.options);
  } catch (const InputError& error) {
    throw in_request(error, "dataset_id");
  }
  if (result.cancelled) return stopped_robot_job(live, spec.dataset_id);
  std::optional<robot::PayloadValidation> validation;
  if (!loaded.held_out.empty()) {
    try {
      validation = robot::validate_payload(model, arm, result, loaded.held_out, spec.options);
    } catch (const InputError& error) {
      throw in_request(error, "validation_dataset_id");
    }
  }
  nlohmann::ordered_json json = api::payload_to_json(model, result, spec.options, arm_source, validation);
  name_runs(json, spec);
  json["arm_job_id"] = spec.arm_job_id.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(spec.arm_job_id);
  json["arm_point"] = api::arm_point_json(model, arm);
  JobOutcome outcome;
  outcome.dataset_id = spec.dataset_id;
  outcome.state = api::JobState::succeeded;
  outcome.result = json.dump();
  for (std::size_t i = 0; i < robot::PayloadResult::names().size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    const double error = result.std_errors[k];
    outcome.estimates.push_back({robot::PayloadResult::names()[i], result.estimate[k],
                                 std::isfinite(error) ? std::optional<double>(error) : std::nullopt});
  }
  return outcome;
}

/// Points of the predicted torque an excitation's result carries for drawing (the page's joint charts).
constexpr long kExcitationTorquePoints = 1000;

/// An excitation design: the trajectory sampled into a dataset (stored idempotently under the job's id,
/// like a simulation's) and the coefficients in the result.
JobOutcome run_excitation_job(const api::JobInfo& job, store::Store& store, LiveJob& live, const RunnerOptions& options) {
  const auto started = Clock::now();
  api::ExcitationSpec spec = api::excitation_from_json(nlohmann::json::parse(job.request));
  const auto robot = store.find_robot(api::all_owners, spec.robot_id);
  const std::shared_ptr<const api::ParsedRobot> stored = stored_robot(store, options, robot);
  if (!stored) {
    return failed(api::problem_to_json({api::ProblemKind::not_found, "robot " + spec.robot_id + " was deleted before the job ran",
                                        "robot_id"})
                      .dump());
  }
  const api::ParsedRobot& parsed = *stored;
  robot::ExcitationOptions design_options = api::excitation_options(spec, parsed.model);
  // Four fifths of the job's time for the search: the rest is for the final figures (two SVDs and the
  // limits' checks: milliseconds for an arm, seconds for a 50-joint design with 20 harmonics).
  design_options.max_seconds = std::min(design_options.max_seconds, 0.8 * options.job_time_limit_seconds);
  design_options.cancel = &live.cancel;
  design_options.progress = [&live](const robot::ExcitationProgress& progress) {
    live.evaluations.store(progress.evaluation + 1, std::memory_order_relaxed);
    if (std::isfinite(progress.best_value)) live.best_cost.store(progress.best_value, std::memory_order_relaxed);
  };
  const robot::ExcitationLimits limits = robot::excitation_limits(parsed.model, design_options);
  const robot::ExcitationDesign design = robot::design_excitation(parsed.model, design_options);
  // The design has no history to stream; its progress is stored once, so a finished job still says how
  // much work it took (the live counters vanish with the run).
  live.evaluations.store(design.summary.evaluations, std::memory_order_relaxed);
  heed(store.record_progress(live.lease, design.summary.evaluations,
                             std::isfinite(design.summary.final_value) ? std::optional<double>(design.summary.final_value)
                                                                       : std::nullopt,
                             {}),
       live);
  JobOutcome outcome;
  if (design.summary.termination == robot::ExcitationTermination::cancelled) {
    if (live.shutdown.load()) {
      outcome.requeue = true;
      return outcome;
    }
    outcome.state = api::JobState::cancelled;
    return outcome;
  }
  const robot::SampledExcitation sampled = robot::sample_excitation(design, spec.dt, spec.periods);
  // Submission checked the series' samples; the ramps from a start pose, known only now, add theirs.
  api::limits::check_dataset_size(static_cast<long long>(sampled.t.size()), parsed.model.joint_count(), 3, "start_pose",
                             "the excitation's ramps, duration / dt");
  if (const auto violation = robot::first_limit_violation(limits, sampled, &parsed.model)) {
    return failed(job_failed("the designed trajectory leaves " + robot::describe(*violation)));
  }
  const std::string name = spec.name.empty() ? "excitation " + robot->name + " (" + job.id + ")" : spec.name;
  const api::IdempotencyKey key{"job-output:" + job.id, job.id};
  const api::DatasetInfo dataset =
      store.insert_dataset(job.owner, name, robot::to_trajectory(sampled), job.id, key).dataset;
  outcome.state = api::JobState::succeeded;
  outcome.dataset_id = dataset.id;
  outcome.result = nlohmann::ordered_json{
      {"dataset_id", dataset.id},
      {"robot_id", spec.robot_id},
      {"samples", dataset.samples},
      {"dt", dataset.dt},
      {"periods", spec.periods},
      {"condition_number", design.summary.condition_number},
      {"ramp_duration", sampled.ramp_duration},
      {"coefficients", api::excitation_to_json(parsed.model, design_options, limits, design)},
      {"torque", api::excitation_torque_json(parsed.model, limits, sampled, kExcitationTorquePoints)},
      {"wall_seconds", std::chrono::duration<double>(Clock::now() - started).count()},
  }.dump();
  return outcome;
}

}  // namespace

api::JobShape job_shape(api::JobKind kind, const std::string& request_json, store::Store& store,
                        const api::OwnerScope& scope) {
  return api::job_shape(
      kind, nlohmann::json::parse(request_json), [&](const std::string& id) { return store.find_dataset(scope, id); },
      [&](const std::string& id) -> std::optional<int> {
        if (const auto robot = store.find_robot(scope, id)) return robot->joints;
        return std::nullopt;
      });
}

namespace {

/// What a kind's run is given.
struct JobRun {
  const api::JobInfo& job;
  store::Store& store;
  LiveJob& live;
  const RunnerOptions& options;
  const JobClock& clock;
};

/// The server's side of each job kind (the api side: api/job_kinds.h), indexed by api::JobKind.
struct KindRunner {
  api::JobKind kind;
  JobOutcome (*run)(const JobRun& run);
};

constexpr std::array<KindRunner, std::size(api::kJobKinds)> kRunners = {{
    {api::JobKind::simulation, [](const JobRun& run) { return run_simulation_job(run.job, run.store, run.live, run.clock); }},
    {api::JobKind::identification,
     [](const JobRun& run) { return run_identification_job(run.job, run.store, run.live, run.options, run.clock); }},
    {api::JobKind::excitation,
     [](const JobRun& run) { return run_excitation_job(run.job, run.store, run.live, run.options); }},
    {api::JobKind::robot_identification,
     [](const JobRun& run) { return run_robot_identification_job(run.job, run.store, run.live, run.options); }},
    {api::JobKind::payload_identification,
     [](const JobRun& run) { return run_payload_identification_job(run.job, run.store, run.live, run.options); }},
}};

constexpr bool runners_in_kind_order() {
  for (std::size_t i = 0; i < kRunners.size(); ++i) {
    if (kRunners[i].kind != api::kJobKinds[i] || static_cast<std::size_t>(api::kJobKinds[i]) != i) return false;
  }
  return true;
}
static_assert(runners_in_kind_order(), "kRunners has one entry per JobKind, in its order");

JobOutcome run_kind(const api::JobInfo& job, store::Store& store, LiveJob& live, const RunnerOptions& options,
                    const JobClock& clock) {
  try {
    return kRunners.at(static_cast<std::size_t>(job.kind)).run({job, store, live, options, clock});
  } catch (const SimulationStopped& stopped) {
    return stopped_simulation(live, clock, stopped);
  } catch (const InputError& error) {
    // Submission validated the request against the data it knew; this catches what only the
    // run can see (a dataset replaced in between, a model that rejects the data).
    return failed(api::problem_to_json(api::problem_from(error)).dump());
  } catch (const api::ApiError& error) {
    return failed(api::problem_to_json(error.problem()).dump());
  } catch (const IdentificationError& error) {
    return failed(api::problem_to_json({api::ProblemKind::not_computable, error.what(), ""}).dump());
  } catch (const std::bad_alloc&) {
    return failed(job_failed("out of memory"));
  } catch (const store::StoreError& error) {
    // SQLite's own text ("string or blob too big", "disk I/O error") is for the log only.
    JobOutcome outcome = failed(job_failed("the job's data could not be read or written (a storage error; see the server log)"));
    outcome.log = std::string("storage error: ") + error.what();
    return outcome;
  } catch (const nlohmann::json::exception& error) {
    JobOutcome outcome = failed(job_failed("internal error while reading the job's request or result; see the server log"));
    outcome.log = std::string("internal error: ") + error.what();
    return outcome;
  } catch (const std::exception& error) {
    // The core's own messages ("simulation: the closed loop diverged near t = ..."): for people.
    return failed(job_failed(error.what()));
  } catch (...) {
    return failed(job_failed("unknown error"));
  }
}

}  // namespace

JobOutcome run_job(const api::JobInfo& job, store::Store& store, LiveJob& live, const RunnerOptions& options) {
  const JobClock clock{Clock::now(), options.job_time_limit_seconds};
  JobOutcome outcome;
  {
    const TimeLimit limit(live, options.job_time_limit_seconds);
    outcome = run_kind(job, store, live, options, clock);
  }
  // Stopped by its time limit (not by a user or a shutdown, and not finished first): failed, saying so.
  if (live.timed_out.load() && !outcome.requeue && outcome.state == api::JobState::cancelled) {
    JobOutcome ended = timed_out(clock, api::job_kind_handler(job.kind).doing);
    ended.dataset_id = outcome.dataset_id;
    return ended;
  }
  return outcome;
}

}  // namespace manipid::server::jobs

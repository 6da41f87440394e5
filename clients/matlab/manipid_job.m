function job = manipid_job(url, job_id, wait)
%MANIPID_JOB  A job's current state: progress while it runs, result or error when it ends.
%   JOB = MANIPID_JOB(URL, JOB_ID) returns the job struct of GET /v1/jobs/{id}:
%   id, kind (simulation, identification: the paper's preset, robot_identification:
%   a URDF robot's, payload_identification: a payload on its tip link, excitation), state (queued, running, succeeded, failed, cancelled), created_at,
%   started_at, finished_at, attempts, dataset_id, progress.evaluations,
%   progress.best_cost, request, and result (when it succeeded or was cancelled)
%   or error (a problem struct, when it failed).
%   JOB = MANIPID_JOB(URL, JOB_ID, WAIT) long-polls: the service answers when the job
%   ends or after WAIT seconds (at most 30).
%
%   URL is 'http://HOST:PORT', or a struct with fields url, token (for a server
%   started with --token; default: the environment variable MANIPID_TOKEN) and
%   timeout (s, per request; default 60). JOB_ID is 'job_...' or a job struct.
%
%   See also manipid_wait, manipid_result, manipid_cancel.
if nargin < 2
  error('manipid:usage', 'usage: job = manipid_job(url, job_id, wait)');
end
id = manipid_id(job_id, 'job');
path = ['/v1/jobs/' id];
timeout = [];
if nargin >= 3 && ~isempty(wait)
  wait = max(0, min(30, double(wait)));
  path = sprintf('%s?wait=%g', path, wait);
  timeout = wait + 60;
end
job = manipid_request(url, 'GET', path, [], cell(0, 2), timeout);
end

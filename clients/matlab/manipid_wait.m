function job = manipid_wait(url, job_id, timeout, varargin)
%MANIPID_WAIT  Wait for a job to end, printing its progress; returns the finished job.
%   JOB = MANIPID_WAIT(URL, JOB_ID) long-polls GET /v1/jobs/{id}?wait= until the job
%   is succeeded, failed or cancelled, and prints a line whenever its state or
%   progress changes (about once a second while it runs), e.g.
%       job_8c1d2e3f4a5b6c7d running: 812 evaluations, best cost 0.0123 (1.0 s)
%       job_8c1d2e3f4a5b6c7d succeeded: 1640 evaluations, best cost 1.05e-05 (1.6 s)
%   JOB = MANIPID_WAIT(URL, JOB_ID, TIMEOUT) gives up after TIMEOUT seconds
%   (default 600) with the error manipid:TIMEOUT; the job keeps running.
%   Options (name-value): 'Quiet', true prints nothing; 'Interval', S prints at
%   most every S seconds (default 1; the wait ends as soon as the job does anyway).
%
%   JOB is the job struct (see manipid_job) with its result. A cancelled job is
%   returned normally (state 'cancelled'); a failed job raises its error:
%   identifier manipid:CODE (usually manipid:JOB_FAILED) with the service's detail.
%
%   Example:
%       job = manipid_wait(url, manipid_identify(url, ds), 120);
%       r = manipid_result(url, job);
%
%   See also manipid_job, manipid_result, manipid_cancel.
if nargin < 2
  error('manipid:usage', 'usage: job = manipid_wait(url, job_id, timeout)');
end
if nargin < 3 || isempty(timeout), timeout = 600; end
options = manipid_options(varargin, struct('Quiet', false, 'Interval', 1), 'manipid_wait');
id = manipid_id(job_id, 'job');
start = tic;
printed = '';
while true
  remaining = timeout - toc(start);
  job = manipid_job(url, id, max(0, min(options.Interval, remaining)));
  finished = any(strcmp(job.state, {'succeeded', 'failed', 'cancelled'}));
  if ~options.Quiet
    line = progress_line(job);
    if ~strcmp(line, printed)
      fprintf('%s (%.1f s)\n', line, toc(start));
      if manipid_is_octave(), fflush(stdout); end
      printed = line;
    end
  end
  if finished, break; end
  if toc(start) >= timeout
    manipid_error('TIMEOUT', 'wait', sprintf('job %s is still %s after %g s (it keeps running; wait again or cancel it)', ...
                  id, job.state, timeout), 0);
  end
end
if strcmp(job.state, 'failed')
  problem = struct('type', '', 'title', '', 'status', 0, 'detail', sprintf('job %s failed', id), ...
                   'code', 'JOB_FAILED', 'field', '', 'instance', ['/v1/jobs/' id]);
  if isfield(job, 'error') && isstruct(job.error)
    names = fieldnames(job.error);
    for k = 1:numel(names)
      problem.(names{k}) = job.error.(names{k});
    end
  end
  if isempty(problem.field), problem.field = ''; end
  manipid_error(problem.code, problem.field, sprintf('job %s failed: %s', id, problem.detail), problem.status, problem);
end
end

function line = progress_line(job)
line = sprintf('%s %s', job.id, job.state);
% Evaluations count for the preset's optimisers (kind identification); a robot_identification (linear)
% has none.
if isfield(job, 'progress') && isstruct(job.progress) && strcmp(job.kind, 'identification')
  evaluations = job.progress.evaluations;
  if isempty(evaluations), evaluations = 0; end
  line = sprintf('%s: %d evaluations', line, evaluations);
  if ~isempty(job.progress.best_cost)
    line = sprintf('%s, best cost %.6g', line, job.progress.best_cost);
  end
end
end

function job = manipid_cancel(url, job_id)
%MANIPID_CANCEL  Cancel a job (best effort, idempotent); returns the job.
%   JOB = MANIPID_CANCEL(URL, JOB_ID) asks the service to cancel the job. A queued
%   job ends 'cancelled' at once; a running identification stops at its next cost
%   evaluation and keeps the best point reached as its result (manipid_result then
%   returns it, with cancelled = true); a finished job is returned unchanged.
%   Follow with manipid_wait(URL, JOB_ID) to see it end.
%
%   See also manipid_wait, manipid_result, manipid_identify.
if nargin < 2
  error('manipid:usage', 'usage: job = manipid_cancel(url, job_id)');
end
id = manipid_id(job_id, 'job');
job = manipid_request(url, 'POST', ['/v1/jobs/' id '/cancel'], []);
end

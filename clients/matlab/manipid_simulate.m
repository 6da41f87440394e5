function job = manipid_simulate(url, options, varargin)
%MANIPID_SIMULATE  Submit a closed-loop simulation of a preset robot; the job makes a dataset.
%   JOB = MANIPID_SIMULATE(URL) simulates the paper's run (cedro2009 preset, 9.7 s,
%   dt = 1 ms, no noise). JOB = MANIPID_SIMULATE(URL, OPTIONS) with OPTIONS a struct
%   whose fields are the JSON fields of POST /v1/simulations, one to one (see
%   api/openapi.yaml, SimulationRequest), for example
%       opts = struct('preset', 'cedro2009', 'duration', 5, 'name', 'short run');
%       opts.noise = struct('q_sigma', 1e-4, 'seed', 7);
%       opts.parameters = struct('m2', 30);
%       opts.kp = [2000 1000 500 100];
%   Fields set to [] are left out. JOB = MANIPID_SIMULATE(..., 'IdempotencyKey', KEY)
%   makes a retry return the first job.
%
%   JOB is the queued job; after JOB = manipid_wait(URL, JOB), JOB.result.dataset_id
%   (also JOB.dataset_id) names the dataset it made; pass JOB itself to
%   manipid_identify or manipid_dataset.
%
%   Example:
%       sim = manipid_wait(url, manipid_simulate(url, struct('preset', 'cedro2009')));
%       job = manipid_identify(url, sim);
%
%   See also manipid_wait, manipid_identify, manipid_dataset.
if nargin < 1
  error('manipid:usage', 'usage: job = manipid_simulate(url, options)');
end
if nargin < 2 || isempty(options), options = struct(); end
if ~isstruct(options) || numel(options) ~= 1
  manipid_error('INVALID_FIELD', '', 'options must be a struct whose fields are the request fields', 0);
end
settings = manipid_options(varargin, struct('IdempotencyKey', ''), 'manipid_simulate');
headers = cell(0, 2);
if ~isempty(settings.IdempotencyKey)
  headers(end + 1, :) = {'Idempotency-Key', settings.IdempotencyKey};
end
job = manipid_request(url, 'POST', '/v1/simulations', manipid_json(options, ''), headers);
end

function job = manipid_identify(url, dataset, options, varargin)
%MANIPID_IDENTIFY  Submit an identification of a robot's parameters; returns the queued job.
%   JOB = MANIPID_IDENTIFY(URL, DATASET) identifies from an uploaded dataset with the
%   paper's settings (all 8 parameters of the cedro2009 robot free, input-error
%   method, BOBYQA, filter chosen from the data) - exactly what
%   `manipid identify run.csv` does. DATASET is a dataset id ('ds_...'), the struct
%   manipid_upload returned, or a finished simulation job (its dataset is used).
%   JOB = MANIPID_IDENTIFY(URL, DATASET, OPTIONS) adds the identification options:
%   a struct whose fields are the JSON request fields of POST /v1/identifications,
%   one to one (see api/openapi.yaml, IdentificationRequest), for example
%       opts.preset = 'cedro2009';
%       opts.free = {'m2', 'm3', 'm4', 'l2', 'l3', 'l4'};   % or 'm2' for one
%       opts.initial = struct('m2', 24, 'l3', 0.55);
%       opts.method = 'output-error';        % input-error | output-error | two-stage
%       opts.half_length = 100; opts.band = 0.2;
%       opts.max_evaluations = 5000;
%   Fields set to [] are left out (the service's default applies); unknown fields
%   are refused by the service (manipid:INVALID_FIELD naming the field).
%   JOB = MANIPID_IDENTIFY(URL, [], OPTIONS) with OPTIONS.simulation set simulates
%   and identifies in one job: struct('simulation', struct('preset', 'cedro2009')).
%   JOB = MANIPID_IDENTIFY(..., 'IdempotencyKey', KEY): a retry with the same KEY and
%   the same request returns the first job (a different request: IDEMPOTENCY_MISMATCH).
%
%   JOB is the job struct (id, kind, state 'queued', links, ...). Follow it with
%   manipid_wait(URL, JOB) and manipid_result(URL, JOB).
%
%   See also manipid_wait, manipid_result, manipid_history, manipid_cancel, manipid_upload.
if nargin < 2
  error('manipid:usage', 'usage: job = manipid_identify(url, dataset_id, options)');
end
if nargin < 3 || isempty(options), options = struct(); end
if ~isstruct(options) || numel(options) ~= 1
  manipid_error('INVALID_FIELD', '', 'options must be a struct whose fields are the request fields', 0);
end
settings = manipid_options(varargin, struct('IdempotencyKey', ''), 'manipid_identify');
request = struct();
if ~isempty(dataset)
  if isfield(options, 'dataset_id') && ~isempty(options.dataset_id)
    manipid_error('INVALID_FIELD', 'dataset_id', 'give the dataset either as the argument or as options.dataset_id, not both', 0);
  end
  request.dataset_id = manipid_id(dataset, 'dataset');
end
names = fieldnames(options);
for k = 1:numel(names)
  if ~(strcmp(names{k}, 'dataset_id') && isfield(request, 'dataset_id'))
    request.(names{k}) = options.(names{k});
  end
end
headers = cell(0, 2);
if ~isempty(settings.IdempotencyKey)
  headers(end + 1, :) = {'Idempotency-Key', settings.IdempotencyKey};
end
job = manipid_request(url, 'POST', '/v1/identifications', manipid_json(request, ''), headers);
end

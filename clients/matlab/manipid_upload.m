function dataset = manipid_upload(url, t_or_dt, q, tau, ref, name, varargin)
%MANIPID_UPLOAD  Upload a measured (or simulated) trajectory to the manipid service.
%   DS = MANIPID_UPLOAD(URL, T_OR_DT, Q) uploads joint angles Q (rad), a
%   samples-by-joints matrix (one row per sample, one column per joint, as
%   measurements are usually held). T_OR_DT is either the sample times (s), a
%   vector with one element per row of Q, or the sample period dt (s), a scalar.
%   DS = MANIPID_UPLOAD(URL, T_OR_DT, Q, TAU, REF, NAME) adds the joint torques TAU
%   (N*m) and the reference angles REF (rad) of the PD loop, both the size of Q
%   (or [] to leave them out), and a NAME for the dataset.
%   DS = MANIPID_UPLOAD(..., 'IdempotencyKey', KEY) makes a retry with the same KEY
%   and the same data return the first dataset instead of storing a second one.
%   DS = MANIPID_UPLOAD(..., 't0', T0) gives the first sample time when T_OR_DT is dt.
%   DS = MANIPID_UPLOAD(..., 'qd', QD, 'qdd', QDD) adds the joint rates (rad/s) and
%   accelerations (rad/s^2) as logged, both the size of Q (kept with the data).
%   Time stamps may jitter, as a real logger's do: the dataset is stored as measured
%   (DS.uniform is false) and an identification resamples it.
%
%   The matrices are sent as the service's per-joint arrays (q(:,j) is joint j),
%   exactly (17 significant digits), so one joint (N-by-1) and one-row shapes keep
%   their meaning. NaN or Inf anywhere raises manipid:INVALID_FIELD before anything
%   is sent (field 'q[1]' for the second joint, as the service names it).
%
%   URL is 'http://HOST:PORT' or a struct with fields url and token (see
%   manipid_job). DS is the dataset struct: id, name, joints, samples, dt,
%   has_torque, has_reference, created_at, links.
%
%   Example:
%       M = dlmread('run.csv', ',', 1, 0);            % t,q1..q4,tau1..tau4,ref1..ref4
%       ds = manipid_upload('http://127.0.0.1:8080', M(:,1), M(:,2:5), M(:,6:9), M(:,10:13), 'run 42');
%       job = manipid_identify('http://127.0.0.1:8080', ds.id, struct('preset', 'cedro2009'));
%
%   See also manipid_identify, manipid_dataset, manipid_simulate.
if nargin < 3
  error('manipid:usage', 'usage: ds = manipid_upload(url, t_or_dt, q, tau, ref, name)');
end
if nargin < 4, tau = []; end
if nargin < 5, ref = []; end
if nargin < 6 || isempty(name), name = ''; end
options = manipid_options(varargin, struct('IdempotencyKey', '', 't0', [], 'qd', [], 'qdd', []), 'manipid_upload');

if ~(isnumeric(q) || islogical(q)) || ndims(q) ~= 2 || isempty(q)
  manipid_error('INVALID_FIELD', 'q', 'q must be a non-empty numeric matrix, samples x joints', 0);
end
[samples, joints] = size(q);

parts = {};
if ~isempty(name)
  parts{end + 1} = ['"name":' manipid_json(name, 'name')];
end
if ~isnumeric(t_or_dt) || isempty(t_or_dt)
  manipid_error('INVALID_FIELD', 't', 'give the sample times (a vector) or the sample period dt (a scalar)', 0);
elseif isscalar(t_or_dt) && samples ~= 1
  parts{end + 1} = ['"dt":' manipid_json(t_or_dt, 'dt')];
  if ~isempty(options.t0)
    parts{end + 1} = ['"t0":' manipid_json(options.t0, 't0')];
  end
else
  if ~isvector(t_or_dt) || numel(t_or_dt) ~= samples
    hint = '';
    if numel(t_or_dt) == joints
      hint = sprintf('; q looks like joints x samples: pass q.'' (%d x %d)', joints, samples);
    end
    manipid_error('INVALID_FIELD', 't', sprintf('t has %d elements but q has %d rows (samples)%s', ...
                  numel(t_or_dt), samples, hint), 0);
  end
  parts{end + 1} = ['"t":' manipid_json(t_or_dt, 't', 'array')];
end
parts{end + 1} = ['"q":' manipid_json(q, 'q', 'columns')];
extra = {'qd', options.qd; 'qdd', options.qdd; 'tau', tau; 'ref', ref};
for k = 1:size(extra, 1)
  value = extra{k, 2};
  if isempty(value), continue; end
  if ~isequal(size(value), [samples joints])
    manipid_error('INVALID_FIELD', extra{k, 1}, sprintf('%s is %d x %d, expected %d x %d like q (samples x joints)', ...
                  extra{k, 1}, size(value, 1), size(value, 2), samples, joints), 0);
  end
  parts{end + 1} = ['"' extra{k, 1} '":' manipid_json(value, extra{k, 1}, 'columns')]; %#ok<AGROW>
end
body = ['{' strjoin(parts, ',') '}'];

headers = cell(0, 2);
if ~isempty(options.IdempotencyKey)
  headers(end + 1, :) = {'Idempotency-Key', options.IdempotencyKey};
end
dataset = manipid_request(url, 'POST', '/v1/datasets', body, headers, 120);
end

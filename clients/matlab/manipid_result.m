function result = manipid_result(url, job_id)
%MANIPID_RESULT  The result of a finished job, with MATLAB-friendly shapes.
%   R = MANIPID_RESULT(URL, JOB_ID) returns the result of an identification:
%     R.estimates        struct of the estimates by name: R.estimates.m2 (kg), .l3 (m); NaN for
%                        a parameter the data cannot determine alone (see R.identifiability)
%     R.std_errors       struct by name; NaN for fixed and unidentifiable parameters
%     R.names, R.values, R.std_values
%                        the same as a 1-by-n cell of names and two 1-by-n vectors
%     R.identifiability  .all_identifiable (logical), .unidentifiable (cell, e.g.
%                        {'m1','l1'}), .combinations (struct array: name, value,
%                        std_error, e.g. 'm1*l1^2'), .findings (cell of sentences),
%                        .singular_values
%     R.correlation      .parameters (cell), .matrix (NaN where undefined)
%     R.free, R.warnings (cells), R.initial (struct), R.initial_cost, R.final_cost,
%     R.evaluations, R.simulations, R.stop_reason, R.cancelled, R.filter,
%     R.method, R.algorithm, R.torque_source, R.wall_seconds, R.dataset_id
%     R.job_id, R.state  the job's id and final state
%   A robot identification (manipid_identify with 'Robot') gives, by name:
%     R.base_names, R.base_values, R.base_std
%                        the base parameters: a 1-by-b cell of names - a standard
%                        parameter such as 'fv2', or the combination the data determine,
%                        such as 'my2 - 0.316*m3 - mz3' - and two 1-by-b vectors (std NaN
%                        where there is none); R.base_parameters is the same as a struct
%                        array (name, estimate, std_error, relative_std_error, data_share)
%     R.base_share       1-by-b: the share of each estimate the data determine (0..1; the
%                        rest is the URDF's value)
%     R.friction         struct array per joint: joint (its URDF name), fv, fc, fo, Ia
%                        (NaN for the terms not identified)
%     R.point, R.prior   structs of every standard parameter by name (m1, mx1, ...,
%                        Izz7, fv1, ...): the estimate nearest to the URDF's values (what
%                        manipid_identified_urdf writes), and the URDF's own values
%     R.validation       with 'Validate': relative_error and rms_error (1-by-fitted
%                        joints), overall_relative_error, and .prior: the same for the
%                        URDF's values - under R.judge (cutoff_hz, trim_seconds)
%     R.fit              residual_rms, relative_error, rms_error (1-by-fitted joints),
%                        overall_relative_error, under R.judge
%     R.correlation (matrix, NaN where undefined), R.condition_number, R.unexcited,
%     R.unidentifiable, R.torque_joints, R.warnings (cells), R.filters, R.selection
%     (what held-out prediction chose), R.robot_id, R.dataset_id
%   A payload identification (manipid_identify_payload) gives:
%     R.detected         true when the mass exceeds two standard errors (or was given): a
%                        run without a payload gives false, R.mass about 0 within its error
%     R.mass, R.mass_std_error            kg
%     R.centre_of_mass, R.centre_of_mass_std_errors
%                        1-by-3, m, in the tip link's frame (NaN when nothing is detected)
%     R.inertia, R.inertia_std
%                        3-by-3 about the centre of mass, tip-link axes, kg m^2
%                        (R.inertia_about_com: the URDF entries ixx ... izz)
%     R.parameter_names, R.parameter_values, R.parameter_std, R.parameter_share
%                        the 10 parameters about the tip link's origin (m, mx, ..., Izz)
%     R.consistent       the payload is a real rigid body (R.consistency_findings: why not);
%                        R.physical with 'Physical', true
%     R.undetermined, R.warnings (cells), R.fit (arm_only_error, with_payload_error),
%     R.validation (arm_only, with_payload), R.arm, R.arm_job_id, R.robot_id, R.dataset_id
%   For a simulation job, R is its result (dataset_id, joints, samples, dt, ...); for
%   an excitation, its dataset_id, samples, condition_number and coefficients.
%   A cancelled identification returns the best point it reached (R.cancelled true).
%
%   JOB_ID is 'job_...' or a job struct; a finished job struct (from manipid_wait)
%   is used as it is, without another request. A job still queued or running
%   raises manipid:NOT_FINISHED; a failed one raises its error (manipid:JOB_FAILED).
%
%   Example:
%       r = manipid_result(url, manipid_wait(url, job));
%       fprintf('m2 = %.4f +- %.2g kg\n', r.estimates.m2, r.std_errors.m2);
%
%   See also manipid_wait, manipid_history, manipid_identify.
if nargin < 2
  error('manipid:usage', 'usage: r = manipid_result(url, job_id)');
end
if isstruct(job_id) && isfield(job_id, 'state') && isfield(job_id, 'result') ...
    && any(strcmp(job_id.state, {'succeeded', 'cancelled'}))
  job = job_id;
else
  job = manipid_job(url, job_id);
end
switch job.state
  case {'queued', 'running'}
    manipid_error('NOT_FINISHED', 'id', sprintf('job %s is %s: call manipid_wait first', job.id, job.state), 0);
  case 'failed'
    manipid_wait(url, job, 0, 'Quiet', true);   % raises the job's error
end
if ~isfield(job, 'result') || ~isstruct(job.result)
  manipid_error('NOT_FOUND', 'result', sprintf('job %s (%s) has no result', job.id, job.state), 0);
end
result = job.result;
if isfield(result, 'estimates') && isstruct(result.estimates)
  result = tidy_identification(result);
elseif isfield(result, 'base_parameters') && (isstruct(result.base_parameters) || iscell(result.base_parameters))
  result = tidy_robot_identification(result);
elseif isfield(result, 'detected') && isfield(result, 'parameters')
  result = tidy_payload(result);
end
result.job_id = job.id;
result.state = job.state;
end

function r = tidy_identification(r)
r.names = fieldnames(r.estimates)';
% A parameter the data cannot determine alone (null in JSON, [] after jsondecode) is NaN.
for k = 1:numel(r.names)
  if isempty(r.estimates.(r.names{k})), r.estimates.(r.names{k}) = NaN; end
end
r.values = cellfun(@(name) r.estimates.(name), r.names);
if ~isfield(r, 'std_errors') || ~isstruct(r.std_errors)
  r.std_errors = struct();
end
r.std_values = nan(size(r.values));
for k = 1:numel(r.names)
  name = r.names{k};
  if ~isfield(r.std_errors, name) || isempty(r.std_errors.(name))
    r.std_errors.(name) = NaN;
  end
  r.std_values(k) = r.std_errors.(name);
end
for name = {'free', 'warnings'}
  if isfield(r, name{1}), r.(name{1}) = manipid_cellstr(r.(name{1})); end
end
if isfield(r, 'identifiability') && isstruct(r.identifiability)
  id = r.identifiability;
  if isfield(id, 'unidentifiable'), id.unidentifiable = manipid_cellstr(id.unidentifiable); end
  if isfield(id, 'findings'), id.findings = manipid_cellstr(id.findings); end
  if isfield(id, 'singular_values'), id.singular_values = reshape(double(id.singular_values), 1, []); end
  if isfield(id, 'combinations')
    id.combinations = struct_array(id.combinations, {'name', 'value', 'std_error'});
  end
  r.identifiability = id;
end
if isfield(r, 'correlation') && isstruct(r.correlation)
  c = r.correlation;
  if isfield(c, 'parameters'), c.parameters = manipid_cellstr(c.parameters); end
  if isfield(c, 'matrix') && iscell(c.matrix)
    c.matrix = numeric_matrix(c.matrix);
  end
  r.correlation = c;
end
end

function r = tidy_robot_identification(r)
r.base_parameters = struct_array(r.base_parameters, {'name', 'estimate', 'std_error', 'relative_std_error', 'data_share'});
r.base_names = {r.base_parameters.name};
r.base_values = [r.base_parameters.estimate];
r.base_std = [r.base_parameters.std_error];
r.base_share = [r.base_parameters.data_share];
if isempty(r.base_parameters)
  r.base_values = zeros(1, 0);
  r.base_std = zeros(1, 0);
  r.base_share = zeros(1, 0);
end
if isfield(r, 'friction')
  r.friction = struct_array(r.friction, {'joint', 'fv', 'fc', 'fo', 'Ia'});
end
for name = {'warnings', 'unexcited', 'unidentifiable', 'torque_joints'}
  if isfield(r, name{1}), r.(name{1}) = manipid_cellstr(r.(name{1})); end
end
if isfield(r, 'correlation') && iscell(r.correlation)
  r.correlation = numeric_matrix(r.correlation);
elseif isfield(r, 'correlation') && isempty(r.correlation)
  r.correlation = zeros(0, 0);
end
if isfield(r, 'condition_number') && isempty(r.condition_number), r.condition_number = NaN; end
for block = {'fit', 'validation'}
  if isfield(r, block{1}) && isstruct(r.(block{1}))
    r.(block{1}) = per_joint_rows(r.(block{1}));
    if isfield(r.(block{1}), 'prior') && isstruct(r.(block{1}).prior)
      r.(block{1}).prior = per_joint_rows(r.(block{1}).prior);
    end
  end
end
end

function figures = per_joint_rows(figures)
%PER_JOINT_ROWS  Per-joint figures as 1-by-joints rows (jsondecode gives columns), null as NaN.
for name = {'residual_rms', 'relative_error', 'rms_error'}
  if isfield(figures, name{1}), figures.(name{1}) = reshape(double(figures.(name{1})), 1, []); end
end
if isfield(figures, 'overall_relative_error') && isempty(figures.overall_relative_error)
  figures.overall_relative_error = NaN;
end
end

function r = tidy_payload(r)
r.mass = number(r.mass);
r.mass_std_error = number(r.mass_std_error);
r.centre_of_mass = numbers(r.centre_of_mass);
r.centre_of_mass_std_errors = numbers(r.centre_of_mass_std_errors);
r.inertia = tensor(r.inertia_about_com);
r.inertia_std = tensor(r.inertia_std_errors);
r.parameters = struct_array(r.parameters, {'name', 'estimate', 'std_error', 'data_share'});
r.parameter_names = {r.parameters.name};
r.parameter_values = [r.parameters.estimate];
r.parameter_std = [r.parameters.std_error];
r.parameter_share = [r.parameters.data_share];
for name = {'warnings', 'undetermined', 'torque_joints', 'consistency_findings'}
  if isfield(r, name{1}), r.(name{1}) = manipid_cellstr(r.(name{1})); end
end
end

function x = number(value)
%NUMBER  A decoded JSON number, NaN for null.
if isempty(value), x = NaN; else, x = double(value); end
end

function x = numbers(value)
%NUMBERS  A decoded JSON array of numbers (nulls among them) as a 1-by-n row, NaN for null.
if iscell(value)
  x = cellfun(@number, value);
else
  x = double(value);
end
x = reshape(x, 1, []);
end

function I = tensor(entries)
%TENSOR  The symmetric 3-by-3 tensor of URDF entries ixx, ixy, ixz, iyy, iyz, izz (NaN for null).
e = cellfun(@(name) number(entries.(name)), {'ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz'});
I = [e(1) e(2) e(3); e(2) e(4) e(5); e(3) e(5) e(6)];
end

function s = struct_array(value, fields)
%STRUCT_ARRAY  A decoded array of objects as a 1-by-n struct array, null numbers as NaN.
if isempty(value)
  s = repmat(cell2struct(cell(numel(fields), 1), fields, 1), 1, 0);
  return
end
if iscell(value)
  items = value;
else
  items = num2cell(value);
end
s = repmat(cell2struct(cell(numel(fields), 1), fields, 1), 1, numel(items));
for k = 1:numel(items)
  for f = 1:numel(fields)
    if isfield(items{k}, fields{f}), s(k).(fields{f}) = items{k}.(fields{f}); end
  end
  for f = fields
    if ~any(strcmp(f{1}, {'name', 'joint'})) && isempty(s(k).(f{1})), s(k).(f{1}) = NaN; end
  end
end
end

function m = numeric_matrix(rows)
%NUMERIC_MATRIX  Rows of numbers (possibly null) decoded as a cell, as a matrix with NaN.
m = nan(numel(rows), 0);
for i = 1:numel(rows)
  row = rows{i};
  if iscell(row)
    values = nan(1, numel(row));
    for j = 1:numel(row)
      if ~isempty(row{j}), values(j) = row{j}; end
    end
  else
    values = reshape(double(row), 1, []);
  end
  m(i, 1:numel(values)) = values;
end
end

function job = manipid_identify(url, dataset, options, varargin)
%MANIPID_IDENTIFY  Submit an identification of a robot's parameters; returns the queued job.
%   JOB = MANIPID_IDENTIFY(URL, DATASET) identifies from an uploaded dataset with the
%   paper's settings (all 8 parameters of the cedro2009 robot free, input-error
%   method, LM (least squares), filter chosen from the data) - exactly what
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
%   Your own robot (a URDF uploaded with manipid_upload_robot): name-value options,
%   with or without an OPTIONS struct before them,
%       JOB = MANIPID_IDENTIFY(URL, DATASET, 'Robot', RB, 'Validate', DS2, ...)
%   identify RB's base parameters - its links' masses, first moments and inertias as
%   far as the data determine them, and each joint's friction - by linear input-error
%   from DATASET (q and tau of RB's joints; time stamps may jitter) - or from several
%   runs, DATASET a cell of them, each filtered alone and then fitted together:
%     'Robot', RB          'rb_...' or the robot struct
%     'Validate', DS2      runs (one, or a cell) the estimate then predicts (R.validation)
%     'Friction', F        'auto' (the default: chosen by held-out prediction), or any of
%                          viscous, coulomb, offset, as a cell or as 'viscous,coulomb';
%                          {} or 'none': none
%     'Armature', TF       each joint's rotor inertia Ia
%     'Physical', TF       a physically consistent estimate (every link a real body)
%     'Trim', [A B]        seconds dropped at the start and at the end
%     'Dt', S              the resampling period, s (default: the median time step)
%     'Weights', W         'unit' (default) or 'per-joint'
%     'ComparisonCutoff', HZ  the low-pass applied to tau and the regressor alike
%                          (default 'auto': chosen by held-out prediction)
%     'Ridge', R           the relative ridge toward the URDF's values (0: least
%                          squares; default 'auto')
%     'JudgeCutoff', HZ    the fixed low-pass every torque figure is judged under (5)
%     'JudgeTrim', S       seconds the judge drops at each end of a run (0.3)
%     'TorqueJoints', J    the joints with torque sensors, e.g. 1:6 (default: every
%                          joint whose torque is not zero throughout)
%   The differentiation filter's fields (half_length, band) go in OPTIONS; the
%   preset's (method, free, initial, ...) are refused with a robot
%   (manipid:INVALID_FIELD naming the field), and so is a dataset whose joints are
%   not the robot's (field dataset_id, dataset_ids[k] or validation_dataset_id). The
%   result (manipid_result) has the base parameters by name (R.base_names,
%   R.base_values, R.base_std, R.base_share), the friction per joint and the
%   validation figures with the judge they were judged under (R.judge);
%   manipid_identified_urdf writes the estimate into the robot's URDF.
%
%   JOB is the job struct (id, kind, state 'queued', links, ...). Follow it with
%   manipid_wait(URL, JOB) and manipid_result(URL, JOB).
%
%   Example:
%       rb = manipid_upload_robot(url, 'arm.urdf');
%       job = manipid_identify(url, run, 'Robot', rb, 'Friction', 'viscous,coulomb', 'Validate', check);
%       r = manipid_result(url, manipid_wait(url, job));
%
%   See also manipid_wait, manipid_result, manipid_history, manipid_cancel, manipid_upload,
%   manipid_upload_robot, manipid_identified_urdf.
if nargin < 2
  error('manipid:usage', 'usage: job = manipid_identify(url, dataset_id, options)');
end
if nargin >= 3 && (ischar(options) || isa(options, 'string'))
  varargin = [{options}, varargin];         % name-value options without an OPTIONS struct
  options = struct();
end
if nargin < 3 || isempty(options), options = struct(); end
if ~isstruct(options) || numel(options) ~= 1
  manipid_error('INVALID_FIELD', '', 'options must be a struct whose fields are the request fields', 0);
end
defaults = struct('IdempotencyKey', '', 'Robot', [], 'Validate', [], 'Friction', [], 'Armature', [], ...
                  'Physical', [], 'Trim', [], 'Dt', [], 'Weights', [], 'ComparisonCutoff', [], 'Ridge', [], ...
                  'JudgeCutoff', [], 'JudgeTrim', [], 'TorqueJoints', []);
settings = manipid_options(varargin, defaults, 'manipid_identify');
request = struct();
if ~isempty(dataset)
  if isfield(options, 'dataset_id') && ~isempty(options.dataset_id)
    manipid_error('INVALID_FIELD', 'dataset_id', 'give the dataset either as the argument or as options.dataset_id, not both', 0);
  end
  if iscell(dataset)
    request.dataset_ids = cellfun(@(d) manipid_id(d, 'dataset'), dataset, 'UniformOutput', false);
  else
    request.dataset_id = manipid_id(dataset, 'dataset');
  end
end
names = fieldnames(options);
for k = 1:numel(names)
  if ~(strcmp(names{k}, 'dataset_id') && (isfield(request, 'dataset_id') || isfield(request, 'dataset_ids')))
    request.(names{k}) = options.(names{k});
  end
end
% The robot options by their request names; one given both ways is an error.
robot_fields = {'Robot', 'robot_id'; 'Validate', 'validation_dataset_id'; 'Friction', 'friction'; ...
                'Armature', 'armature'; 'Physical', 'physical'; 'Trim', 'trim'; 'Dt', 'dt'; 'Weights', 'weights'; ...
                'ComparisonCutoff', 'comparison_cutoff'; 'Ridge', 'ridge'; 'JudgeCutoff', 'judge_cutoff'; ...
                'JudgeTrim', 'judge_trim'; 'TorqueJoints', 'torque_joints'};
for k = 1:size(robot_fields, 1)
  value = settings.(robot_fields{k, 1});
  field = robot_fields{k, 2};
  if isempty(value) && ~(strcmp(field, 'friction') && iscell(value))
    continue                                % left out: the service's default ({} is "no friction")
  end
  if isfield(request, field) && ~isempty(request.(field))
    manipid_error('INVALID_FIELD', field, sprintf('give %s either as the ''%s'' option or as options.%s, not both', ...
                  field, robot_fields{k, 1}, field), 0);
  end
  switch field
    case 'robot_id'
      value = manipid_id(value, 'robot');
    case 'validation_dataset_id'
      [field, value] = manipid_validation_ids(value);
    case 'torque_joints'
      value = reshape(double(value), 1, []);
    case 'friction'
      value = manipid_friction(value);
    case {'armature', 'physical'}
      value = logical(value);
    case 'trim'
      value = reshape(double(value), 1, []);
  end
  request.(field) = value;
end
if (isfield(request, 'validation_dataset_id') || isfield(request, 'validation_dataset_ids')) && ~isfield(request, 'robot_id')
  manipid_error('INVALID_FIELD', 'validation_dataset_id', ...
                'Validate needs Robot: only robot identifications predict a validation run', 0);
end
headers = cell(0, 2);
if ~isempty(settings.IdempotencyKey)
  headers(end + 1, :) = {'Idempotency-Key', settings.IdempotencyKey};
end
job = manipid_request(url, 'POST', '/v1/identifications', manipid_json(request, ''), headers);
end

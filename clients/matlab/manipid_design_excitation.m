function job = manipid_design_excitation(url, robot, varargin)
%MANIPID_DESIGN_EXCITATION  Submit an excitation design for a robot; the job makes a dataset.
%   JOB = MANIPID_DESIGN_EXCITATION(URL, ROBOT) queues POST /v1/excitations for ROBOT
%   ('rb_...' or the struct manipid_upload_robot returned): per joint a Fourier series
%   (Swevers et al.) that starts and ends at rest, stays within the URDF's position and
%   velocity limits and an acceleration limit, and minimises the condition number of
%   the base regressor. Options (name-value; left out: the service's default):
%     'Period', S            the series' period, s (10)
%     'Harmonics', L         harmonics per joint (5)
%     'Duration', S          s, whole periods (default one period)
%     'Criterion', C         'condition' (minimise) or 'logdet' (maximise log det)
%     'Dt', S                the samples' period, s (0.001; must divide the period)
%     'MaxAcceleration', A   rad/s^2, one value or one per joint (7.5)
%     'PositionMargin', Q    rad kept from each position limit (0.05)
%     'Friction', F          the friction terms the design excites: {'viscous', 'coulomb'}
%                            (default), any of viscous, coulomb, offset, or {} / 'none'
%     'Armature', TF         the model to identify has rotor inertias
%     'Seed', N              the random starts' seed (1)
%     'MaxSeconds', S        the design's time budget, s (30)
%     'Name', NAME           the name of the dataset it makes
%     'IdempotencyKey', K    a retry with the same K and request returns the first job
%
%   Follow it with manipid_wait; then JOB.dataset_id names the trajectory it made and
%   [~, data] = manipid_dataset(URL, JOB) downloads it (data.t, data.q, data.qd,
%   data.qdd, samples x joints) to run on the robot. JOB.result.coefficients holds the
%   series' coefficients, JOB.result.condition_number the criterion reached.
%
%   Example:
%       job = manipid_wait(url, manipid_design_excitation(url, rb, 'Period', 10, 'Duration', 20));
%       [~, trajectory] = manipid_dataset(url, job);
%
%   See also manipid_upload_robot, manipid_dataset, manipid_identify.
if nargin < 2
  error('manipid:usage', 'usage: job = manipid_design_excitation(url, robot, ''Period'', 10, ...)');
end
defaults = struct('Period', [], 'Harmonics', [], 'Duration', [], 'Criterion', [], 'Dt', [], ...
                  'MaxAcceleration', [], 'PositionMargin', [], 'Friction', [], 'Armature', [], ...
                  'Seed', [], 'MaxSeconds', [], 'Name', [], 'IdempotencyKey', '');
options = manipid_options(varargin, defaults, 'manipid_design_excitation');
request = struct('robot_id', manipid_id(robot, 'robot'));
fields = {'Period', 'period'; 'Harmonics', 'harmonics'; 'Duration', 'duration'; 'Criterion', 'criterion'; ...
          'Dt', 'dt'; 'MaxAcceleration', 'max_acceleration'; 'PositionMargin', 'position_margin'; ...
          'Seed', 'seed'; 'MaxSeconds', 'max_seconds'; 'Name', 'name'};
for k = 1:size(fields, 1)
  value = options.(fields{k, 1});
  if ~isempty(value), request.(fields{k, 2}) = value; end
end
if ~isempty(options.Friction) || iscell(options.Friction)
  request.friction = manipid_friction(options.Friction);
end
if ~isempty(options.Armature), request.armature = logical(options.Armature); end
headers = cell(0, 2);
if ~isempty(options.IdempotencyKey)
  headers(end + 1, :) = {'Idempotency-Key', options.IdempotencyKey};
end
job = manipid_request(url, 'POST', '/v1/excitations', manipid_json(request, ''), headers);
end

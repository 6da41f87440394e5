function job = manipid_design_excitation(url, robot, varargin)
%MANIPID_DESIGN_EXCITATION  Submit an excitation design for a robot; the job makes a dataset.
%   JOB = MANIPID_DESIGN_EXCITATION(URL, ROBOT) queues POST /v1/excitations for ROBOT
%   ('rb_...' or the struct manipid_upload_robot returned): per joint a Fourier series
%   (Swevers et al.) that starts and ends at rest, stays within the URDF's position,
%   velocity and effort limits and an acceleration limit, and minimises the condition
%   number of the base regressor. Options (name-value; left out: the service's default):
%     'Period', S            the series' period, s (10)
%     'Harmonics', L         harmonics per joint (5)
%     'Duration', S          s, whole periods (default one period)
%     'Criterion', C         'condition' (minimise) or 'logdet' (maximise log det)
%     'Dt', S                the samples' period, s (0.001; must divide the period)
%     'MaxVelocity', V       rad/s, one value or one per joint (the URDF's)
%     'MaxAcceleration', A   rad/s^2, one value or one per joint (7.5)
%     'MaxJerk', J           rad/s^3, one value or one per joint (none)
%     'MaxTorque', T         N m, one value or one per joint (the URDF's efforts)
%     'TorqueParameters', R  the model whose torque MaxTorque holds: an identification's
%                            result struct (default: the URDF's parameters)
%     'StartPose', Q         rad, one per joint: the run ramps from it and back (none)
%     'PositionMargin', Q    rad kept from each position limit (0.1)
%     'Friction', F          the friction terms the design excites: {'viscous', 'coulomb'}
%                            (default), any of viscous, coulomb, offset, or {} / 'none'
%     'Armature', TF         the model to identify has rotor inertias
%     'Seed', N              the random starts' seed (1)
%     'MaxEvaluations', N    the design's budget (8000): the same result on every machine
%     'MaxSeconds', S        a time cap, s (300)
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
                  'MaxVelocity', [], 'MaxAcceleration', [], 'MaxJerk', [], 'MaxTorque', [], ...
                  'TorqueParameters', [], 'StartPose', [], 'PositionMargin', [], 'Friction', [], ...
                  'Armature', [], 'Seed', [], 'MaxEvaluations', [], 'MaxSeconds', [], 'Name', [], ...
                  'IdempotencyKey', '');
options = manipid_options(varargin, defaults, 'manipid_design_excitation');
request = struct('robot_id', manipid_id(robot, 'robot'));
fields = {'Period', 'period'; 'Harmonics', 'harmonics'; 'Duration', 'duration'; 'Criterion', 'criterion'; ...
          'Dt', 'dt'; 'MaxVelocity', 'max_velocity'; 'MaxAcceleration', 'max_acceleration'; ...
          'MaxJerk', 'max_jerk'; 'MaxTorque', 'max_torque'; 'TorqueParameters', 'torque_parameters'; ...
          'StartPose', 'start_pose'; 'PositionMargin', 'position_margin'; 'Seed', 'seed'; 'MaxEvaluations', 'max_evaluations'; ...
          'MaxSeconds', 'max_seconds'; 'Name', 'name'};
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

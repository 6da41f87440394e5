function job = manipid_identify_payload(url, dataset, robot, varargin)
%MANIPID_IDENTIFY_PAYLOAD  Submit a payload identification (a tool on a robot's tip link); returns the queued job.
%   JOB = MANIPID_IDENTIFY_PAYLOAD(URL, DATASET, ROBOT) identifies a payload - a tool, a
%   gripper, a part rigidly fixed to the tip link of ROBOT (a URDF uploaded with
%   manipid_upload_robot: 'rb_...' or its struct) - from DATASET, a run carrying it (q and
%   tau of the robot's joints; a dataset id or struct, or a cell of several runs): its mass,
%   centre of mass and inertia from the torque the arm leaves unexplained. Without 'Arm'
%   the arm is the URDF's own values. Name-value options:
%     'Arm', JOB           the arm as identified: a finished robot identification of ROBOT
%                          from runs without the payload (manipid_identify with 'Robot';
%                          'job_...' or its struct)
%     'Validate', DS2      runs with the payload (one, or a cell) the arm then predicts with
%                          and without it (R.validation)
%     'Mass', KG           the payload's mass, when known: only the rest is estimated
%     'CentreOfMass', C    its centre of mass [x y z], m, in the tip link's frame, when known
%     'Physical', TF       a real rigid body (mass > 0, inertia about the centre of mass
%                          positive definite), which a URDF and a simulator take; R.consistent
%                          says whether the payload is one either way
%     'Trim', [A B]        seconds dropped at the start and at the end
%     'Dt', S              the resampling period, s (default: the median time step)
%     'ComparisonCutoff', HZ  the residual's low-pass (default: chosen by held-out error)
%     'JudgeCutoff', HZ    the low-pass the torque figures are judged under (5)
%     'JudgeTrim', S       seconds the judge drops at each end of a run (0.3)
%     'TorqueJoints', J    the joints whose torque is fitted, e.g. 1:6 (default: all)
%     'Weights', W         'unit' (default) or 'per-joint': each joint by its residual
%     'IdempotencyKey', K  a retry with the same K and request returns the first job
%   An Arm that is not a succeeded robot identification of ROBOT, a known mass <= 0, a
%   run whose joints are not the robot's: manipid:INVALID_FIELD naming the field
%   (arm_job_id, known_mass, dataset_id, ...), nothing queued. A run without a payload is
%   not an error: its result says R.detected false, R.mass about 0 within R.mass_std_error.
%
%   JOB is the job struct (kind 'payload_identification'). Follow it with
%   manipid_wait(URL, JOB) and manipid_result(URL, JOB): R.mass, R.centre_of_mass,
%   R.inertia (3-by-3 about the centre of mass) with their standard errors, R.detected,
%   R.undetermined, R.warnings, R.fit and R.validation (torque error without and with the
%   payload). manipid_identified_urdf(URL, JOB, FILE) writes the robot's URDF with the
%   payload mounted on its tip link.
%
%   Example:
%       arm = manipid_wait(url, manipid_identify(url, run, 'Robot', rb));
%       job = manipid_identify_payload(url, tool_run, rb, 'Arm', arm);
%       r = manipid_result(url, manipid_wait(url, job));
%       fprintf('%.4f +- %.2g kg at [%g %g %g] m\n', r.mass, r.mass_std_error, r.centre_of_mass);
%
%   See also manipid_identify, manipid_wait, manipid_result, manipid_identified_urdf.
if nargin < 3
  error('manipid:usage', 'usage: job = manipid_identify_payload(url, dataset, robot, ''Arm'', arm_job, ...)');
end
defaults = struct('IdempotencyKey', '', 'Arm', [], 'Validate', [], 'Mass', [], 'CentreOfMass', [], 'Physical', [], 'Trim', [], ...
                  'Dt', [], 'ComparisonCutoff', [], 'JudgeCutoff', [], 'JudgeTrim', [], 'TorqueJoints', [], 'Weights', []);
settings = manipid_options(varargin, defaults, 'manipid_identify_payload');
request = struct('payload', true, 'robot_id', manipid_id(robot, 'robot'));
if iscell(dataset)
  request.dataset_ids = cellfun(@(d) manipid_id(d, 'dataset'), dataset, 'UniformOutput', false);
else
  request.dataset_id = manipid_id(dataset, 'dataset');
end
% The options by their request names.
fields = {'Arm', 'arm_job_id'; 'Validate', 'validation_dataset_id'; 'Mass', 'known_mass'; ...
          'CentreOfMass', 'known_centre_of_mass'; 'Physical', 'physical'; 'Trim', 'trim'; 'Dt', 'dt'; 'ComparisonCutoff', 'comparison_cutoff'; ...
          'JudgeCutoff', 'judge_cutoff'; 'JudgeTrim', 'judge_trim'; 'TorqueJoints', 'torque_joints'; 'Weights', 'weights'};
for k = 1:size(fields, 1)
  value = settings.(fields{k, 1});
  field = fields{k, 2};
  if isempty(value)
    continue                                % left out: the service's default
  end
  switch field
    case 'arm_job_id'
      value = manipid_id(value, 'job');
    case 'validation_dataset_id'
      [field, value] = manipid_validation_ids(value);
    case {'known_centre_of_mass', 'trim', 'torque_joints'}
      value = reshape(double(value), 1, []);
    case 'physical'
      value = logical(value);
  end
  request.(field) = value;
end
headers = cell(0, 2);
if ~isempty(settings.IdempotencyKey)
  headers(end + 1, :) = {'Idempotency-Key', settings.IdempotencyKey};
end
job = manipid_request(url, 'POST', '/v1/identifications', manipid_json(request, ''), headers);
end

function robot = manipid_tidy_robot(robot)
%MANIPID_TIDY_ROBOT  (private) A decoded robot resource with MATLAB-friendly shapes.
%   joints as a 1-by-n struct array (whatever jsondecode made of it), joint_names as a
%   1-by-n cell, warnings and parameters.names as cells.
if ~isstruct(robot), return; end
if isfield(robot, 'joints')
  joints = robot.joints;
  if iscell(joints)
    joints = [joints{:}];
  end
  robot.joints = reshape(joints, 1, []);
  robot.joint_names = arrayfun(@(joint) joint.name, robot.joints, 'UniformOutput', false);
end
if isfield(robot, 'warnings'), robot.warnings = manipid_cellstr(robot.warnings); end
if isfield(robot, 'parameters') && isstruct(robot.parameters) && isfield(robot.parameters, 'names')
  robot.parameters.names = manipid_cellstr(robot.parameters.names);
end
end

function [robot, urdf] = manipid_robot(url, robot_id)
%MANIPID_ROBOT  An uploaded robot's description and, if asked, its URDF document.
%   RB = MANIPID_ROBOT(URL, ROBOT_ID) returns the robot struct of GET /v1/robots/{id}
%   (the fields manipid_upload_robot describes: joints, joint_names, parameters, ...).
%   [RB, URDF] = MANIPID_ROBOT(URL, ROBOT_ID) also returns the URDF document exactly as
%   uploaded (GET /v1/robots/{id}?format=urdf), as text.
%   ROBOT_ID is 'rb_...' or the struct manipid_upload_robot returned. An unknown id
%   raises manipid:NOT_FOUND.
%
%   See also manipid_upload_robot, manipid_identified_urdf.
if nargin < 2
  error('manipid:usage', 'usage: [rb, urdf] = manipid_robot(url, robot_id)');
end
id = manipid_id(robot_id, 'robot');
robot = manipid_tidy_robot(manipid_request(url, 'GET', ['/v1/robots/' id]));
if nargout > 1
  urdf = manipid_request(url, 'GET', ['/v1/robots/' id '?format=urdf'], [], {'Accept', 'application/xml'}, 120);
end
end

function robot = manipid_upload_robot(url, file, varargin)
%MANIPID_UPLOAD_ROBOT  Upload a robot's URDF to the manipid service; returns the robot.
%   RB = MANIPID_UPLOAD_ROBOT(URL, FILE) sends the URDF file FILE as it is
%   (POST /v1/robots, Content-Type application/xml); the service keeps it byte for
%   byte (manipid_robot gives it back). FILE may also be the document itself: text
%   that starts with '<'.
%   Options (name-value):
%     'Name', NAME          the robot's name (default: the URDF's robot name)
%     'Base', LINK          the link fixed to the world (default: the URDF's root)
%     'Tip', LINK           the link that ends the chain (default: the only leaf)
%     'IdempotencyKey', K   a retry with the same K and document returns the first
%                           robot; a key from the file's content makes a script safe
%                           to re-run (a different document: IDEMPOTENCY_MISMATCH)
%
%   RB is the robot struct: id ('rb_...'), name, robot_name, base_link, tip_link,
%   joints (struct array: name, link, type, axis, limits, damping, friction), gravity,
%   parameters.names (m1 mx1 my1 mz1 Ixx1 ... fv1 ... fc1 ...), parameters.urdf_values,
%   base_parameters.count, warnings (cell), created_at, and joint_names (a cell of the
%   moving joints' names, k = 1..n). A URDF the service cannot use raises
%   manipid:INVALID_FIELD with field 'urdf' (or 'base', 'tip') and the reason.
%
%   Example:
%       rb = manipid_upload_robot(url, 'arm.urdf', 'Name', 'lab arm');
%       job = manipid_identify(url, ds, 'Robot', rb, 'Friction', {'viscous', 'coulomb'});
%
%   See also manipid_robot, manipid_identify, manipid_design_excitation.
if nargin < 2
  error('manipid:usage', 'usage: rb = manipid_upload_robot(url, file, ''Name'', name, ...)');
end
options = manipid_options(varargin, struct('Name', '', 'Base', '', 'Tip', '', 'IdempotencyKey', ''), ...
                          'manipid_upload_robot');
if isa(file, 'string'), file = char(file); end
if ~ischar(file) || isempty(file) || size(file, 1) ~= 1
  manipid_error('INVALID_FIELD', 'urdf', 'give the URDF file''s name, or the document as text', 0);
end
first = regexp(file, '\S', 'once');
if ~isempty(first) && file(first) == '<'
  document = file;
else
  if ~exist(file, 'file')
    manipid_error('INVALID_FIELD', 'urdf', sprintf('no URDF file %s', file), 0);
  end
  document = fileread(file);     % Octave: the bytes as they are; MATLAB: the UTF-8 text
end
query = {};
for name = {'Name', 'Base', 'Tip'}
  value = options.(name{1});
  if isa(value, 'string'), value = char(value); end
  if ~isempty(value)
    query{end + 1} = [lower(name{1}) '=' manipid_percent_encode(value)]; %#ok<AGROW>
  end
end
path = '/v1/robots';
if ~isempty(query), path = [path '?' strjoin(query, '&')]; end
headers = {'Content-Type', 'application/xml'};
if ~isempty(options.IdempotencyKey)
  headers(end + 1, :) = {'Idempotency-Key', options.IdempotencyKey};
end
robot = manipid_tidy_robot(manipid_request(url, 'POST', path, document, headers, 120));
end

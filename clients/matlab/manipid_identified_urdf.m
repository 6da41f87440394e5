function urdf = manipid_identified_urdf(url, job_id, file)
%MANIPID_IDENTIFIED_URDF  The robot's URDF with a robot identification's estimate (or a payload) written in.
%   URDF = MANIPID_IDENTIFIED_URDF(URL, JOB_ID) returns GET /v1/jobs/{id}/urdf: the
%   robot's own document, each body's <inertial> (mass, centre of mass, inertia) and
%   each joint's <dynamics> (damping = fv, friction = fc) replaced by the estimate's
%   values (R.point of manipid_result), everything else as it was. The service writes
%   it; nothing is computed here. For a payload identification (manipid_identify_payload):
%   the robot's document with the payload mounted on its tip link, a fixed link
%   manipid_payload holding its mass, centre of mass and inertia.
%   MANIPID_IDENTIFIED_URDF(URL, JOB_ID, FILE) also writes it to FILE, byte for byte.
%
%   Errors: manipid:CONFLICT (HTTP 409) when the job is not a succeeded robot or payload
%   identification, its robot was deleted, a body of the estimate is not a real rigid
%   body (field 'physical': a URDF cannot hold it; identify with 'Physical', true), or a
%   payload identification found no payload.
%
%   Example:
%       job = manipid_wait(url, manipid_identify(url, ds, 'Robot', rb));
%       manipid_identified_urdf(url, job, 'arm_identified.urdf');
%
%   See also manipid_identify, manipid_result, manipid_robot.
if nargin < 2
  error('manipid:usage', 'usage: urdf = manipid_identified_urdf(url, job_id, file)');
end
id = manipid_id(job_id, 'job');
urdf = manipid_request(url, 'GET', ['/v1/jobs/' id '/urdf'], [], {'Accept', 'application/xml'}, 120);
if nargin >= 3 && ~isempty(file)
  fid = fopen(file, 'w');
  if fid < 0
    manipid_error('INVALID_FIELD', 'file', sprintf('cannot write %s', file), 0);
  end
  if manipid_is_octave()
    fwrite(fid, urdf, 'uint8');                          % Octave: the bytes as received
  else
    fwrite(fid, unicode2native(urdf, 'UTF-8'), 'uint8'); % MATLAB: the text as UTF-8
  end
  fclose(fid);
end
end

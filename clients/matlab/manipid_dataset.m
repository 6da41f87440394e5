function [dataset, data] = manipid_dataset(url, dataset_id)
%MANIPID_DATASET  A stored dataset's metadata and, if asked, its samples as arrays.
%   DS = MANIPID_DATASET(URL, DATASET_ID) returns the metadata of GET
%   /v1/datasets/{id}: id, name, joints, samples, dt, uniform (false: jittery time
%   stamps, resampled when identified), has_torque, has_reference, has_rates,
%   has_accelerations, source_job (the simulation or excitation that made it, or []),
%   created_at, links.
%   [DS, DATA] = MANIPID_DATASET(URL, DATASET_ID) also downloads the samples
%   (?format=csv, bit-exact) as samples-by-joints arrays, the layout manipid_upload
%   takes:
%     DATA.t    samples-by-1 sample times (s)
%     DATA.q    samples-by-joints joint angles (rad)
%     DATA.qd   samples-by-joints joint rates (rad/s), [] when the dataset has none
%     DATA.qdd  samples-by-joints joint accelerations (rad/s^2), [] when none
%     DATA.tau  samples-by-joints torques (N*m), [] when the dataset has none
%     DATA.ref  samples-by-joints reference angles (rad), [] when none
%   DATASET_ID is 'ds_...', a dataset struct, or a finished simulation or excitation
%   job (an excitation's trajectory: t, q, qd, qdd to run on the robot).
%
%   Example:
%       [ds, data] = manipid_dataset(url, sim);     % sim: a finished simulation job
%       plot(data.t, data.q);
%
%   See also manipid_upload, manipid_simulate.
if nargin < 2
  error('manipid:usage', 'usage: [ds, data] = manipid_dataset(url, dataset_id)');
end
id = manipid_id(dataset_id, 'dataset');
dataset = manipid_request(url, 'GET', ['/v1/datasets/' id]);
if nargout < 2
  return
end
text = manipid_request(url, 'GET', ['/v1/datasets/' id '?format=csv'], [], {'Accept', 'text/csv'}, 120);
newline_at = find(text == 10, 1);
if isempty(newline_at)
  manipid_error('INTERNAL', 'format', sprintf('dataset %s: the CSV has no header line', id), 0);
end
columns = strtrim(strsplit(text(1:newline_at - 1), ','));
values = sscanf(strrep(text(newline_at + 1:end), ',', ' '), '%f');
if mod(numel(values), numel(columns)) ~= 0
  manipid_error('INTERNAL', 'format', sprintf('dataset %s: the CSV does not have %d numbers per row', id, numel(columns)), 0);
end
table = reshape(values, numel(columns), []).';
data = struct('t', table(:, strcmp(columns, 't')), ...
              'q', table(:, pick(columns, 'q')), ...
              'qd', table(:, pick(columns, 'qd')), ...
              'qdd', table(:, pick(columns, 'qdd')), ...
              'tau', table(:, pick(columns, 'tau')), ...
              'ref', table(:, pick(columns, 'ref')));
for name = {'qd', 'qdd', 'tau', 'ref'}
  if isempty(data.(name{1})), data.(name{1}) = []; end
end
end

function mask = pick(columns, prefix)
mask = ~cellfun(@isempty, regexp(columns, ['^' prefix '\d+$'], 'once'));
end

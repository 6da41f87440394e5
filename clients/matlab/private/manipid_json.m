function text = manipid_json(value, path, mode)
%MANIPID_JSON  (private) JSON text of a MATLAB value, for the service's request bodies.
%   TEXT = MANIPID_JSON(VALUE, PATH) encodes VALUE; PATH names it in error messages
%   the way the service does (simulation.noise.q_sigma, kp[1]).
%   TEXT = MANIPID_JSON(VALUE, PATH, 'array') always gives a JSON array, even for a
%   scalar or a single string.
%   TEXT = MANIPID_JSON(M, PATH, 'columns') gives one array per column of the matrix M
%   ([[M(:,1)...],[M(:,2)...]]): the service's per-joint layout, whatever the size of
%   M (one joint, one sample).
%
%   Unlike jsonencode, the shape never depends on the size: arrays stay arrays. Rules:
%   struct -> object (fields that are [] are left out: the service's default applies);
%   struct array -> array of objects; cell -> array; char row -> string;
%   logical/numeric scalar -> true/false/number; vector -> array; matrix -> array of
%   rows. The fields free, kp, kd, step_times, amplitudes, dataset_ids, validation_dataset_ids,
%   torque_joints and start_pose are always arrays.
%   NaN and Inf are refused (error manipid:INVALID_FIELD naming the element): they are
%   not JSON and never go on the wire. Numbers are written so that they read back to
%   the same double (shortest of %.15g / %.17g; bulk arrays use %.17g).
if nargin < 2, path = ''; end
if nargin < 3, mode = ''; end
switch mode
  case 'columns'
    text = encode_columns(value, path);
  case 'array'
    text = encode(value, path, true);
  otherwise
    text = encode(value, path, false);
end
end

function text = encode(value, path, as_array)
if isa(value, 'string')            % MATLAB string arrays (Octave has none)
  if isscalar(value) && ~as_array
    value = char(value);
  else
    value = cellstr(value);
  end
end
if isstruct(value)
  if numel(value) == 1 && ~as_array
    text = encode_object(value, path);
  else
    parts = cell(1, numel(value));
    for k = 1:numel(value)
      parts{k} = encode_object(value(k), sprintf('%s[%d]', path, k - 1));
    end
    text = ['[' strjoin(parts, ',') ']'];
  end
elseif iscell(value)
  parts = cell(1, numel(value));
  for k = 1:numel(value)
    parts{k} = encode(value{k}, sprintf('%s[%d]', path, k - 1), false);
  end
  text = ['[' strjoin(parts, ',') ']'];
elseif ischar(value)
  if size(value, 1) > 1
    fail(path, sprintf('%s is a character matrix; give a row of characters or a cell array of them', label(path)));
  end
  text = quote(value);
  if as_array, text = ['[' text ']']; end
elseif islogical(value)
  words = {'false', 'true'};
  if isscalar(value) && ~as_array
    text = words{double(value) + 1};
  else
    text = ['[' strjoin(words(double(value(:)') + 1), ',') ']'];
  end
elseif isnumeric(value)
  if ~isreal(value)
    fail(path, sprintf('%s is complex', label(path)));
  end
  if isscalar(value) && ~as_array
    text = numbers(value, path);
  elseif isvector(value) || isempty(value)
    text = ['[' numbers(value, path) ']'];
  else
    rows = cell(1, size(value, 1));
    for r = 1:size(value, 1)
      rows{r} = ['[' numbers(value(r, :), sprintf('%s[%d]', path, r - 1)) ']'];
    end
    text = ['[' strjoin(rows, ',') ']'];
  end
else
  fail(path, sprintf('%s has a type (%s) that has no JSON form', label(path), class(value)));
end
end

function text = encode_object(value, path)
array_keys = {'free', 'kp', 'kd', 'step_times', 'amplitudes', 'dataset_ids', 'validation_dataset_ids', 'torque_joints', 'start_pose'};
names = fieldnames(value);
parts = {};
for k = 1:numel(names)
  item = value.(names{k});
  if isnumeric(item) && isequal(size(item), [0 0])
    continue                       % [] leaves the field out
  end
  if isempty(path)
    child = names{k};
  else
    child = [path '.' names{k}];
  end
  parts{end + 1} = [quote(names{k}) ':' encode(item, child, any(strcmp(names{k}, array_keys)))]; %#ok<AGROW>
end
text = ['{' strjoin(parts, ',') '}'];
end

function text = encode_columns(matrix, path)
if ~(isnumeric(matrix) || islogical(matrix)) || ~isreal(matrix) || ndims(matrix) > 2
  fail(path, sprintf('%s must be a real numeric matrix (samples x joints)', label(path)));
end
columns = cell(1, size(matrix, 2));
for j = 1:size(matrix, 2)
  columns{j} = ['[' numbers(matrix(:, j), sprintf('%s[%d]', path, j - 1), sprintf('%s(:,%d)', path, j)) ']'];
end
text = ['[' strjoin(columns, ',') ']'];
end

function text = numbers(value, path, shown)
%NUMBERS  Comma-separated numbers (no brackets); refuses NaN and Inf.
if nargin < 3, shown = path; end
value = double(value(:)');
bad = find(~isfinite(value), 1);
if ~isempty(bad)
  if numel(value) == 1
    where = label(shown);
  else
    where = sprintf('%s (element %d)', label(shown), bad);
  end
  fail(path, sprintf('%s is %s: NaN and Inf are not JSON numbers; remove or fill the missing samples before sending', ...
                     where, num2str(value(bad))));
end
if isempty(value)
  text = '';
elseif numel(value) > 64
  text = sprintf('%.17g,', value);
  text(end) = [];
else
  parts = cell(1, numel(value));
  for k = 1:numel(value)
    s = sprintf('%.15g', value(k));
    if str2double(s) ~= value(k)
      s = sprintf('%.17g', value(k));
    end
    parts{k} = s;
  end
  text = strjoin(parts, ',');
end
end

function text = quote(s)
s = strrep(s, '\', '\\');
s = strrep(s, '"', '\"');
codes = double(s);
if any(codes < 32)
  out = cell(1, numel(s));
  for k = 1:numel(s)
    if codes(k) < 32
      out{k} = sprintf('\\u%04x', codes(k));
    else
      out{k} = s(k);
    end
  end
  s = [out{:}];
end
text = ['"' s '"'];
end

function s = label(path)
if isempty(path)
  s = 'the request';
else
  s = path;
end
end

function fail(path, detail)
manipid_error('INVALID_FIELD', path, detail, 0);
end

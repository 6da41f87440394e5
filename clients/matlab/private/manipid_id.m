function id = manipid_id(value, what)
%MANIPID_ID  (private) The id of a dataset or job given as text or as the struct the service returned.
%   ID = MANIPID_ID(VALUE, 'job') accepts 'job_...' or a job struct (field id).
%   ID = MANIPID_ID(VALUE, 'dataset') accepts 'ds_...', a dataset struct (field id), or
%   a finished simulation or excitation job (the dataset it made).
%   ID = MANIPID_ID(VALUE, 'robot') accepts 'rb_...' or a robot struct.
%   The id is checked against the service's pattern ^[A-Za-z0-9_-]{1,64}$ so that it is safe in a URL path.
if isa(value, 'string'), value = char(value); end
if isstruct(value) && numel(value) == 1
  if strcmp(what, 'dataset') && isfield(value, 'kind') && any(strcmp(value.kind, {'simulation', 'excitation'}))
    id = '';
    if isfield(value, 'dataset_id') && ischar(value.dataset_id), id = value.dataset_id; end
    if isempty(id) && isfield(value, 'result') && isstruct(value.result) && isfield(value.result, 'dataset_id')
      id = value.result.dataset_id;
    end
    if isempty(id)
      manipid_error('NOT_FINISHED', 'dataset_id', sprintf(['%s %s has not made its dataset yet: ' ...
                    'call manipid_wait first'], value.kind, value.id), 0);
    end
  elseif isfield(value, 'id')
    id = value.id;
  else
    id = [];
  end
else
  id = value;
end
if ~ischar(id) || isempty(regexp(id, '^[A-Za-z0-9_-]{1,64}$', 'once'))
  manipid_error('INVALID_FIELD', [what '_id'], sprintf(['expected a %s id (text such as ''%s'') ' ...
                'or the struct the service returned for it'], what, example(what)), 0);
end
end

function text = example(what)
switch what
  case 'job'
    text = 'job_8c1d2e3f4a5b6c7d';
  case 'robot'
    text = 'rb_0f1e2d3c4b5a6978';
  otherwise
    text = 'ds_3f2a9c0d1b7e4a55';
end
end

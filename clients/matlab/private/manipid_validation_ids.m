function [field, value] = manipid_validation_ids(value)
%MANIPID_VALIDATION_IDS  (private) A request's validation datasets, as the service takes them.
%   [FIELD, VALUE] = MANIPID_VALIDATION_IDS(VALUE): one dataset (id or struct) gives
%   'validation_dataset_id' and its id; a cell of them 'validation_dataset_ids' and a cell of ids.
  if iscell(value)
    field = 'validation_dataset_ids';
    value = cellfun(@(d) manipid_id(d, 'dataset'), value, 'UniformOutput', false);
  else
    field = 'validation_dataset_id';
    value = manipid_id(value, 'dataset');
  end
end

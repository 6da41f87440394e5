function options = manipid_options(arguments, defaults, caller)
%MANIPID_OPTIONS  (private) Name-value pairs (case-insensitive names) over a struct of defaults.
options = defaults;
names = fieldnames(defaults);
if mod(numel(arguments), 2) ~= 0
  manipid_error('INVALID_FIELD', '', sprintf('%s: name-value arguments must come in pairs', caller), 0);
end
for k = 1:2:numel(arguments)
  name = arguments{k};
  if isa(name, 'string'), name = char(name); end
  match = [];
  if ischar(name), match = find(strcmpi(names, name), 1); end
  if isempty(match)
    manipid_error('INVALID_FIELD', char(name), sprintf('%s: unknown option; accepted: %s', caller, strjoin(names', ', ')), 0);
  end
  options.(names{match}) = arguments{k + 1};
end
end

function terms = manipid_friction(value)
%MANIPID_FRICTION  (private) Friction terms as a cell for the request's array.
%   {'viscous', 'coulomb'}, 'viscous,coulomb' or 'viscous' -> a 1-by-n cell of names;
%   'none', '' or {} -> {} (the JSON array [], no friction); 'auto' -> 'auto' (chosen by
%   held-out prediction, the service's default).
if isa(value, 'string'), value = cellstr(value); end
if ischar(value) && strcmp(strtrim(value), 'auto')
  terms = 'auto';
  return
end
if ischar(value)
  value = strtrim(strsplit(value, ','));
  value = value(~cellfun(@isempty, value));
end
if ~iscell(value) || ~all(cellfun(@ischar, value))
  manipid_error('INVALID_FIELD', 'friction', ...
                'Friction must be ''auto'' or a cell of viscous, coulomb, offset (or ''viscous,coulomb''; {} or ''none'' for none)', 0);
end
terms = reshape(value, 1, []);
if isequal(terms, {'none'}), terms = {}; end
end

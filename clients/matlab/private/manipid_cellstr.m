function c = manipid_cellstr(value)
%MANIPID_CELLSTR  (private) A decoded JSON array of strings as a 1-by-n cell array, whatever its size.
%   jsondecode gives [] for [], a cell for ["a","b"]; this gives {} and {'a','b'}.
if isempty(value)
  c = {};
elseif ischar(value)
  c = {value};
elseif iscell(value)
  c = reshape(value, 1, []);
else
  c = reshape(num2cell(value), 1, []);
end
end

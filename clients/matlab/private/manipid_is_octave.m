function tf = manipid_is_octave()
%MANIPID_IS_OCTAVE  (private) True when running in GNU Octave, false in MATLAB.
persistent cached
if isempty(cached)
  cached = exist('OCTAVE_VERSION', 'builtin') ~= 0;
end
tf = cached;
end

function problem = manipid_last_problem(new_problem)
%MANIPID_LAST_PROBLEM  The problem+json details of the last manipid error.
%   P = MANIPID_LAST_PROBLEM() returns the problem of the last error raised by a
%   manipid_* function, as a struct with the fields of the service's
%   application/problem+json answer: type, title, status, detail, code, field,
%   instance ([] before any error). Client-side errors (status 0) have the same
%   fields: codes INVALID_FIELD (bad input, nothing was sent), CONNECTION (no
%   answer), TIMEOUT, NOT_FINISHED (result of an unfinished job).
%
%   The error itself carries the same information: its identifier is
%   'manipid:CODE' and its message 'manipid CODE (field F, HTTP S): detail', so
%
%       try
%           manipid_identify(url, ds, struct('free', {{'m9'}}));
%       catch err
%           if strcmp(err.identifier, 'manipid:INVALID_FIELD')
%               p = manipid_last_problem();   % p.field is 'free[0]'
%           end
%       end
%
%   MANIPID_LAST_PROBLEM(P) sets it (used internally).
%
%   See also manipid_upload, manipid_identify, manipid_wait.
persistent last
if nargin > 0
  last = new_problem;
end
problem = last;
end

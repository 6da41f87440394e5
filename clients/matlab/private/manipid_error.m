function manipid_error(code, field, detail, status, problem)
%MANIPID_ERROR  (private) Raise the error for a problem+json answer (or a client-side one).
%   manipid_error(CODE, FIELD, DETAIL, STATUS) raises an error with identifier
%   'manipid:CODE' and the message 'manipid CODE (field FIELD, HTTP STATUS): DETAIL'.
%   manipid_error(..., PROBLEM) keeps the whole problem struct for manipid_last_problem.
%   STATUS is 0 for errors found before anything was sent (client side).
if nargin < 4 || isempty(status), status = 0; end
if isempty(code) || ~ischar(code) || isempty(regexp(code, '^[A-Za-z][A-Za-z0-9_]*$', 'once'))
  code = 'UNKNOWN';
end
if nargin < 5 || isempty(problem)
  problem = struct('type', '', 'title', '', 'status', status, 'detail', detail, ...
                   'code', code, 'field', field, 'instance', '');
end
manipid_last_problem(problem);
where = {};
if ~isempty(field), where{end+1} = ['field ' field]; end
if status > 0, where{end+1} = sprintf('HTTP %d', status); end
message = ['manipid ' code];
if ~isempty(where), message = [message ' (' strjoin(where, ', ') ')']; end
message = [message ': ' detail];
error(struct('identifier', ['manipid:' code], 'message', message));
end

function [data, status, headers] = manipid_request(server, method, path, body, extra_headers, timeout)
%MANIPID_REQUEST  (private) One HTTP request to the manipid service; the only place that talks HTTP.
%   [DATA, STATUS, HEADERS] = MANIPID_REQUEST(SERVER, METHOD, PATH, BODY, EXTRA_HEADERS, TIMEOUT)
%   SERVER         the base URL ('http://127.0.0.1:8080') or a struct with fields url and,
%                  optionally, token and timeout (s). Without a token, the environment
%                  variable MANIPID_TOKEN is used when set.
%   METHOD         'GET', 'POST', 'DELETE'.
%   PATH           '/v1/...' with its query string (already encoded).
%   BODY           JSON text to send, or [] for none (a POST without a body is sent
%                  with Content-Length: 0).
%   EXTRA_HEADERS  n-by-2 cell of header names and values (Idempotency-Key, Accept).
%   TIMEOUT        seconds for the whole exchange ([]: the server's timeout or 60).
%   DATA is the decoded JSON (struct) for JSON answers and the text otherwise.
%   HEADERS is an n-by-2 cell of the answer's header names (lower case) and values.
%   Any 4xx/5xx answer raises manipid:CODE from its problem+json (see manipid_error);
%   no answer raises manipid:CONNECTION (or manipid:TIMEOUT).
%
%   MATLAB uses matlab.net.http (R2016b+), which gives the status and body of error
%   answers. Octave 7's webread/webwrite cannot be used: they discard the body of
%   4xx answers ("HTTP response code said error"), webwrite turns a text body into
%   form fields, and weboptions rejects several HeaderFields. Octave therefore runs
%   the curl program (MANIPID_CURL, default 'curl') with a config file, so that no
%   header or token appears on a command line.
if nargin < 4, body = []; end
if nargin < 5 || isempty(extra_headers), extra_headers = cell(0, 2); end
if nargin < 6, timeout = []; end

[base, token, default_timeout] = parse_server(server);
if isempty(timeout), timeout = default_timeout; end
url = [base path];

fields = cell(0, 2);
if ~any(strcmpi(extra_headers(:, 1), 'Accept'))
  fields(end + 1, :) = {'Accept', 'application/json'};
end
if ~isempty(body) && ~any(strcmpi(extra_headers(:, 1), 'Content-Type'))
  fields(end + 1, :) = {'Content-Type', 'application/json'};
end
if ~isempty(token)
  fields(end + 1, :) = {'Authorization', ['Bearer ' token]};
end
fields = [fields; extra_headers];
for k = 1:size(fields, 1)
  if ~ischar(fields{k, 2}) || any(fields{k, 2} == 10 | fields{k, 2} == 13)
    manipid_error('INVALID_FIELD', fields{k, 1}, sprintf('the %s header must be one line of text', fields{k, 1}), 0);
  end
end

if manipid_is_octave()
  [status, text, headers] = send_with_curl(url, upper(method), body, fields, timeout);
else
  [status, text, headers] = send_with_matlab(url, upper(method), body, fields, timeout);
end

content_type = '';
row = find(strcmp(headers(:, 1), 'content-type'), 1);
if ~isempty(row), content_type = lower(headers{row, 2}); end
is_json = ~isempty(strfind(content_type, 'json'));

if status >= 400
  problem = [];
  if is_json && ~isempty(text)
    try
      problem = jsondecode(text);
    catch
      problem = [];
    end
  end
  if ~isstruct(problem)
    problem = struct('type', '', 'title', '', 'status', status, 'detail', text, ...
                     'code', sprintf('HTTP_%d', status), 'field', '', 'instance', path);
  end
  for name = {'type', 'title', 'detail', 'code', 'field', 'instance'}
    if ~isfield(problem, name{1}) || ~ischar(problem.(name{1}))
      problem.(name{1}) = '';
    end
  end
  if ~isfield(problem, 'status') || isempty(problem.status), problem.status = status; end
  if isempty(problem.code), problem.code = sprintf('HTTP_%d', status); end
  manipid_error(problem.code, problem.field, problem.detail, status, problem);
end

if is_json && ~isempty(text)
  data = jsondecode(text);
else
  data = text;
end
end

function [base, token, timeout] = parse_server(server)
token = '';
timeout = 60;
if isstruct(server)
  if ~isfield(server, 'url')
    manipid_error('INVALID_FIELD', 'url', 'a server struct needs the field url', 0);
  end
  base = server.url;
  if isfield(server, 'token') && ~isempty(server.token), token = server.token; end
  if isfield(server, 'timeout') && ~isempty(server.timeout), timeout = server.timeout; end
else
  base = server;
end
if isa(base, 'string'), base = char(base); end
if ~ischar(base) || isempty(regexp(base, '^https?://[^\s]+$', 'once'))
  manipid_error('INVALID_FIELD', 'url', 'the server URL must look like http://HOST:PORT', 0);
end
while ~isempty(base) && base(end) == '/'
  base(end) = [];
end
if isempty(token)
  token = getenv('MANIPID_TOKEN');
end
end

function [status, text, headers] = send_with_curl(url, method, body, fields, timeout)
config = [tempname() '.curlrc'];
output = [tempname() '.body'];
header_file = [tempname() '.headers'];
errors = [tempname() '.stderr'];
upload = [tempname() '.json'];
files = {config, output, header_file, errors, upload};
cleanup = onCleanup(@() remove_files(files)); %#ok<NASGU>

lines = {['url = ' config_quote(url)], ...
         ['request = ' config_quote(method)], ...
         'silent', 'show-error', ...
         ['output = ' config_quote(output)], ...
         ['dump-header = ' config_quote(header_file)], ...
         'write-out = "%{http_code}"', ...
         'connect-timeout = 10', ...
         sprintf('max-time = %d', ceil(timeout)), ...
         'header = "Expect:"'};
for k = 1:size(fields, 1)
  lines{end + 1} = ['header = ' config_quote([fields{k, 1} ': ' fields{k, 2}])]; %#ok<AGROW>
end
if ~isempty(body) || strcmp(method, 'POST')
  fid = fopen(upload, 'w');
  if fid < 0
    manipid_error('CONNECTION', '', ['cannot write a temporary file ' upload], 0);
  end
  fwrite(fid, body, 'uint8');
  fclose(fid);
  lines{end + 1} = ['data-binary = ' config_quote(['@' upload])];
  if isempty(body)
    lines{end + 1} = 'header = "Content-Type:"';   % no form content type for an empty POST
  end
end
previous_mask = umask(77);        % octal 077: the config may hold the token, keep it private
fid = fopen(config, 'w');
umask(previous_mask);
if fid < 0
  manipid_error('CONNECTION', '', ['cannot write a temporary file ' config], 0);
end
fprintf(fid, '%s\n', lines{:});
fclose(fid);

program = getenv('MANIPID_CURL');
if isempty(program), program = 'curl'; end
command = sprintf('"%s" -q -K "%s" 2>"%s"', program, config, errors);
[rc, written] = system(command);
if rc ~= 0
  message = strtrim(read_text(errors));
  if rc == 28
    manipid_error('TIMEOUT', '', sprintf('no answer from %s within %g s (%s)', url, timeout, message), 0);
  elseif rc == 127
    manipid_error('CONNECTION', '', sprintf('cannot run %s: install curl (Octave needs it) or set MANIPID_CURL', program), 0);
  else
    manipid_error('CONNECTION', '', sprintf('%s %s failed: curl exit %d: %s', method, url, rc, message), 0);
  end
end
status = str2double(strtrim(written));
if isnan(status)
  manipid_error('CONNECTION', '', sprintf('%s %s: unreadable curl status %s', method, url, written), 0);
end
text = read_text(output);
headers = parse_headers(read_text(header_file));
end

function [status, text, headers] = send_with_matlab(url, method, body, fields, timeout)
header = matlab.net.http.HeaderField.empty;
for k = 1:size(fields, 1)
  header(end + 1) = matlab.net.http.HeaderField(fields{k, 1}, fields{k, 2}); %#ok<AGROW>
end
message_body = [];
if ~isempty(body)
  message_body = matlab.net.http.MessageBody();
  message_body.Payload = unicode2native(char(body), 'UTF-8');
elseif strcmp(method, 'POST')
  header(end + 1) = matlab.net.http.field.ContentLengthField(0);   % the service wants a length
end
request = matlab.net.http.RequestMessage(method, header, message_body);
options = matlab.net.http.HTTPOptions('ConnectTimeout', 10, 'ResponseTimeout', timeout, ...
                                      'ConvertResponse', false, 'SavePayload', true);
try
  response = request.send(matlab.net.URI(url), options);
catch err
  if ~isempty(strfind(lower(err.identifier), 'timeout')) || ~isempty(strfind(lower(err.message), 'timed out'))
    manipid_error('TIMEOUT', '', sprintf('no answer from %s within %g s (%s)', url, timeout, err.message), 0);
  end
  manipid_error('CONNECTION', '', sprintf('%s %s failed: %s', method, url, err.message), 0);
end
status = double(response.StatusCode);
text = '';
if ~isempty(response.Body)
  if ~isempty(response.Body.Payload)
    text = native2unicode(reshape(response.Body.Payload, 1, []), 'UTF-8');
  elseif ischar(response.Body.Data) || isa(response.Body.Data, 'string')
    text = char(response.Body.Data);
  elseif isa(response.Body.Data, 'uint8')
    text = native2unicode(reshape(response.Body.Data, 1, []), 'UTF-8');
  end
end
headers = cell(numel(response.Header), 2);
for k = 1:numel(response.Header)
  headers{k, 1} = lower(char(response.Header(k).Name));
  headers{k, 2} = char(response.Header(k).Value);
end
end

function headers = parse_headers(text)
%PARSE_HEADERS  Name/value cell of the last header block curl dumped (after any 100 Continue).
lines = regexp(text, '\r?\n', 'split');
start = find(strncmp(lines, 'HTTP/', 5), 1, 'last');
if isempty(start), start = 0; end
headers = cell(0, 2);
for k = start + 1:numel(lines)
  colon = find(lines{k} == ':', 1);
  if ~isempty(colon)
    headers(end + 1, :) = {lower(strtrim(lines{k}(1:colon - 1))), strtrim(lines{k}(colon + 1:end))}; %#ok<AGROW>
  end
end
end

function text = read_text(file)
text = '';
fid = fopen(file, 'r');
if fid < 0, return; end
text = fread(fid, Inf, 'uint8=>char')';
fclose(fid);
end

function quoted = config_quote(s)
quoted = ['"' strrep(strrep(s, '\', '\\'), '"', '\"') '"'];
end

function remove_files(files)
for k = 1:numel(files)
  if exist(files{k}, 'file')
    delete(files{k});
  end
end
end

function [index, cost, theta, names] = manipid_history(url, job_id, varargin)
%MANIPID_HISTORY  Every cost evaluation of an identification, as arrays.
%   [INDEX, COST, THETA, NAMES] = MANIPID_HISTORY(URL, JOB_ID) pages through
%   GET /v1/jobs/{id}/history (following next_page_token) and returns
%     INDEX  evaluations-by-1, the evaluation numbers 0, 1, 2, ...
%     COST   evaluations-by-1, the cost of each evaluation (NaN if the service had none)
%     THETA  evaluations-by-parameters, the parameter values evaluated (one row each)
%     NAMES  1-by-parameters cell of the column names of THETA ({'m1',...,'l4'})
%   Nothing is decimated: numel(INDEX) equals the result's evaluations. It works
%   while the job runs too (the evaluations so far).
%   Option: 'PageSize', N entries per request (default 1000, the service's maximum).
%
%   Example:
%       [i, c, theta, names] = manipid_history(url, job);
%       semilogy(i, c); [~, best] = min(c); theta(best, strcmp(names, 'm2'))
%
%   See also manipid_result, manipid_wait.
if nargin < 2
  error('manipid:usage', 'usage: [index, cost, theta, names] = manipid_history(url, job_id)');
end
options = manipid_options(varargin, struct('PageSize', 1000), 'manipid_history');
id = manipid_id(job_id, 'job');
index_pages = {};
cost_pages = {};
theta_pages = {};
names = {};
token = '';
while true
  path = sprintf('/v1/jobs/%s/history?page_size=%d', id, round(options.PageSize));
  if ~isempty(token)
    path = [path '&page_token=' manipid_percent_encode(token)]; %#ok<AGROW>
  end
  page = manipid_request(url, 'GET', path);
  [page_index, page_cost, page_theta, names] = decode_page(page.items, names);
  index_pages{end + 1} = page_index; %#ok<AGROW>
  cost_pages{end + 1} = page_cost; %#ok<AGROW>
  theta_pages{end + 1} = page_theta; %#ok<AGROW>
  token = '';
  if isfield(page, 'next_page_token') && ischar(page.next_page_token)
    token = page.next_page_token;
  end
  if isempty(token), break; end
end
index = vertcat(index_pages{:});
cost = vertcat(cost_pages{:});
theta = vertcat(theta_pages{:});
if isempty(index), index = zeros(0, 1); cost = zeros(0, 1); end
if isempty(theta), theta = zeros(numel(index), numel(names)); end
end

function [index, cost, theta, names] = decode_page(items, names)
%DECODE_PAGE  One page of history entries as arrays (fast when jsondecode gave a struct array).
if isempty(items)
  items = {};
end
n = numel(items);
if isempty(names) && n > 0
  first = items(1);
  if iscell(first), first = first{1}; end
  if isfield(first, 'parameters') && isstruct(first.parameters)
    names = fieldnames(first.parameters)';
  end
end
if isstruct(items) && all(isfield(items, {'index', 'cost', 'parameters'}))
  index = [items.index]';
  cost = [items.cost]';
  theta = nan(n, numel(names));
  complete = numel(index) == n && numel(cost) == n;
  if complete && n > 0
    parameters = [items.parameters];
    complete = numel(parameters) == n && all(isfield(parameters, names));
    for k = 1:numel(names)
      if ~complete, break; end
      column = [parameters.(names{k})];
      complete = numel(column) == n;
      if complete, theta(:, k) = column(:); end
    end
  end
  if complete
    index = double(index);
    cost = double(cost);
    return
  end
  items = num2cell(items);
end
% General case: entries of different shapes or with nulls (NaN then).
index = nan(n, 1);
cost = nan(n, 1);
theta = nan(n, numel(names));
for i = 1:n
  item = items{i};
  if isfield(item, 'index') && ~isempty(item.index), index(i) = item.index; end
  if isfield(item, 'cost') && ~isempty(item.cost), cost(i) = item.cost; end
  if isfield(item, 'parameters') && isstruct(item.parameters)
    for k = 1:numel(names)
      if isfield(item.parameters, names{k}) && ~isempty(item.parameters.(names{k}))
        theta(i, k) = item.parameters.(names{k});
      end
    end
  end
end
end

function run_tests(url, run_csv)
%RUN_TESTS  End-to-end test of the MATLAB/Octave client against a running manipid service.
%   RUN_TESTS(URL, RUN_CSV) drives the service at URL through the client: the paper's
%   case (cedro2009) simulated by the service and uploaded from the arrays of RUN_CSV
%   (written by `manipid simulate --out RUN_CSV`), identified, waited for, its result
%   and history checked; shapes of one joint / few samples; Idempotency-Key; cancel;
%   and the error mapping (problem+json code/field, NaN refused before sending).
%   With the environment variables MANIPID_URDF (a 7-joint URDF: examples/robots/
%   panda_like.urdf) and MANIPID_ROBOT_DIR (run.csv, check.csv, tool.csv, tool.json and
%   truth.json made by run_tests.sh with manipid excitation and manipid torque), also the
%   URDF robot functions: upload (byte for byte back, idempotent), identification with
%   friction and validation checked against the truth by name, the identified URDF's
%   masses, a payload on the identified arm checked against the tool's values, an
%   excitation design and its trajectory, and their errors; MANIPID_UR5 (a 6-joint
%   URDF) adds the joint-count mismatch.
%   Without arguments, URL and RUN_CSV come from the environment variables MANIPID_URL
%   and MANIPID_RUN_CSV. When the server was started with --token, MANIPID_TOKEN must
%   hold it (MANIPID_TEST_TOKEN=1 then also checks that a wrong token is refused).
%   Raises an error on the first failure. tests/run_tests.sh starts a server and runs
%   this with octave-cli.
if nargin < 1 || isempty(url), url = getenv('MANIPID_URL'); end
if nargin < 2 || isempty(run_csv), run_csv = getenv('MANIPID_RUN_CSV'); end
if isempty(url) || isempty(run_csv)
  error('run_tests:usage', 'run_tests(URL, RUN_CSV), or set MANIPID_URL and MANIPID_RUN_CSV');
end
here = fileparts(mfilename('fullpath'));
addpath(fileparts(here));
started = tic;
passed = 0;

% --- The paper's run simulated by the service equals `manipid simulate`'s, bit for bit.
M = dlmread(run_csv, ',', 1, 0);
check(isequal(size(M), [9701 13]), 'run.csv is the paper''s run: 9701 samples, t + 4 x (q, tau, ref)');
sim = manipid_simulate(url, struct('preset', 'cedro2009'));
check(strcmp(sim.kind, 'simulation') && any(strcmp(sim.state, {'queued', 'running', 'succeeded'})), ...
      'manipid_simulate returns the job');
sim = manipid_wait(url, sim, 60);
check(strcmp(sim.state, 'succeeded'), 'the simulation succeeds');
[meta, data] = manipid_dataset(url, sim);
check(meta.joints == 4 && meta.samples == 9701 && meta.has_torque && meta.has_reference, ...
      'the simulated dataset has 4 joints, 9701 samples, torques and references');
check(strcmp(meta.source_job, sim.id), 'the dataset names the simulation that made it');
check(isequal(data.t, M(:, 1)) && isequal(data.q, M(:, 2:5)) && isequal(data.tau, M(:, 6:9)) ...
      && isequal(data.ref, M(:, 10:13)), 'the service''s simulation equals manipid simulate''s CSV exactly');
passed = passed + 1;

% --- Upload from arrays (samples x joints), round trip bit-exact.
ds = manipid_upload(url, M(:, 1), M(:, 2:5), M(:, 6:9), M(:, 10:13), 'paper run from Octave');
check(strncmp(ds.id, 'ds_', 3) && ds.joints == 4 && ds.samples == 9701, 'upload: 4 joints, 9701 samples');
check(strcmp(ds.name, 'paper run from Octave') && ds.has_torque && ds.has_reference, 'upload: name, torque, reference');
check(abs(ds.dt - 0.001) < 1e-12, 'upload: dt = 1 ms');
[~, back] = manipid_dataset(url, ds.id);
check(isequal(back.t, M(:, 1)) && isequal(back.q, M(:, 2:5)) && isequal(back.tau, M(:, 6:9)) ...
      && isequal(back.ref, M(:, 10:13)), 'upload: the stored samples are the arrays, bit for bit');
passed = passed + 1;

% --- The paper's identification: submit, wait, result.
job = manipid_identify(url, ds, struct('preset', 'cedro2009'));
check(strcmp(job.kind, 'identification') && strncmp(job.id, 'job_', 4), 'manipid_identify returns the job');
job = manipid_wait(url, job.id, 120);
check(strcmp(job.state, 'succeeded'), 'the identification succeeds');
r = manipid_result(url, job.id);
check(abs(r.estimates.m2 - 25) < 0.01, sprintf('m2 = %.6f, expected 25 within 0.01', r.estimates.m2));
check(isnan(r.estimates.m1) && isnan(r.estimates.l1), 'm1 and l1 have no estimate of their own (NaN): only m1*l1^2 is determined');
check(abs(r.estimates.m3 - 15) < 0.01 && abs(r.estimates.m4 - 5) < 0.01, 'm3 = 15 and m4 = 5 within 0.01');
check(isequal(sort(r.identifiability.unidentifiable), {'l1', 'm1'}), 'm1 and l1 are reported unidentifiable');
check(~r.identifiability.all_identifiable, 'all_identifiable is false');
check(strcmp(r.identifiability.combinations(1).name, 'm1*l1^2') ...
      && abs(r.identifiability.combinations(1).value - 50 * 0.4^2) < 0.01, 'the product m1*l1^2 = 8 is reported');
check(isnan(r.std_errors.m1) && isnan(r.std_errors.l1) && r.std_errors.m2 > 0 && r.std_errors.m2 < 1e-3, ...
      'standard errors: NaN for m1 and l1, small for m2');
check(isequal(r.names, {'m1', 'm2', 'm3', 'm4', 'l1', 'l2', 'l3', 'l4'}) && numel(r.values) == 8 ...
      && r.values(2) == r.estimates.m2 && isnan(r.std_values(1)), 'names/values/std_values follow the estimates');
check(strcmp(r.job_id, job.id) && strcmp(r.state, 'succeeded') && strcmp(r.dataset_id, ds.id), 'result names its job and dataset');
check(isequal(size(r.correlation.matrix), [8 8]) && isnan(r.correlation.matrix(1, 1)) && r.correlation.matrix(2, 2) == 1, ...
      'correlation matrix 8 x 8, NaN for the unidentifiable');
r2 = manipid_result(url, job);
check(isequaln(r2.estimates, r.estimates), 'manipid_result takes the finished job struct as well');
passed = passed + 1;

% --- History: every evaluation, paged.
[index, cost, theta, names] = manipid_history(url, job);
check(numel(index) == r.evaluations && job.progress.evaluations == r.evaluations, ...
      sprintf('history length %d = evaluations %d', numel(index), r.evaluations));
check(isequal(index, (0:r.evaluations - 1)'), 'history indices are 0..evaluations-1');
check(min(cost) == r.final_cost, 'the smallest cost in the history is the final cost');
check(isequal(size(theta), [r.evaluations 8]) && isequal(names, r.names), 'theta is evaluations x 8, names as the estimates');
initial = cellfun(@(n) r.initial.(n), names);
check(isequal(theta(1, :), initial), 'the first evaluation is the initial point');
[index400, cost400, theta400] = manipid_history(url, job.id, 'PageSize', 400);
check(isequal(index400, index) && isequal(cost400, cost) && isequal(theta400, theta), 'pages of 400 give the same history');
passed = passed + 1;

% --- Shapes: one joint, a single free parameter given as text, few samples.
one = manipid_upload(url, [0 0.1 0.2 0.3 0.4], [0; 0.1; 0.2; 0.3; 0.4]);
check(one.joints == 1 && one.samples == 5, 'one joint (5 x 1) stays 1 joint of 5 samples');
odd_name = sprintf('run "7" \\ with\ttab');
two = manipid_upload(url, 0.01, [1 2 3; 4 5 6], [], [], odd_name);
check(strcmp(two.name, odd_name), 'quotes, backslashes and tabs in a name survive JSON');
check(two.joints == 3 && two.samples == 2 && abs(two.dt - 0.01) < 1e-15, 'a 2 x 3 matrix is 2 samples of 3 joints (dt given)');
[~, two_back] = manipid_dataset(url, two);
check(isequal(two_back.q, [1 2 3; 4 5 6]) && isempty(two_back.tau) && isempty(two_back.ref), ...
      'the 2 x 3 dataset comes back as it went, without tau and ref');
truth = struct('m1', 50, 'm2', 24, 'm3', 15, 'm4', 5, 'l1', 0.4, 'l2', 0.8, 'l3', 0.6, 'l4', 0.2);
quick = manipid_identify(url, ds.id, struct('free', 'm2', 'initial', truth, 'max_evaluations', 500, 'lower', []));
check(isequal(quick.request.free, {'m2'}) && quick.request.initial.m2 == 24 && ~isfield(quick.request, 'lower'), ...
      'free ''m2'' goes as ["m2"]; [] fields are left out');
check(quick.request.initial.l3 == 0.6, 'initial values go as given');
quick = manipid_wait(url, quick, 60, 'Quiet', true);
rq = manipid_result(url, quick);
check(isequal(rq.free, {'m2'}) && abs(rq.estimates.m2 - 25) < 0.01, sprintf('one free parameter (the others at their true values): m2 = %.6f, expected 25', rq.estimates.m2));
passed = passed + 1;

% --- Idempotency-Key: the same upload twice is one dataset.
key = sprintf('octave-test-%d', round(rand() * 1e9));
first = manipid_upload(url, 0.01, [1 2 3; 4 5 6], [], [], 'idem', 'IdempotencyKey', key);
again = manipid_upload(url, 0.01, [1 2 3; 4 5 6], [], [], 'idem', 'IdempotencyKey', key);
check(strcmp(first.id, again.id), 'the same Idempotency-Key returns the first dataset');
code = caught(@() manipid_upload(url, 0.01, [1 2 3; 4 5 7], [], [], 'idem', 'IdempotencyKey', key));
check(strcmp(code, 'manipid:IDEMPOTENCY_MISMATCH'), 'the same key with other data: IDEMPOTENCY_MISMATCH');
passed = passed + 1;

% --- Cancel a running output-error identification.
slow = manipid_identify(url, ds, struct('method', 'output-error', 'max_evaluations', 100000, 'max_seconds', 600));
cancelled = manipid_cancel(url, slow);
check(strcmp(cancelled.id, slow.id) && (cancelled.cancel_requested || strcmp(cancelled.state, 'cancelled')), ...
      'manipid_cancel asks for the cancellation');
slow = manipid_wait(url, slow, 60, 'Quiet', true);
check(strcmp(slow.state, 'cancelled'), 'the cancelled job ends cancelled');
passed = passed + 1;

% --- Errors: problem+json code, field and detail in the error; nothing sent for NaN.
[code, message, problem] = caught(@() manipid_identify(url, ds, struct('bogus', 1)));
check(strcmp(code, 'manipid:INVALID_FIELD'), ['unknown option: manipid:INVALID_FIELD, got ' code]);
check(strcmp(problem.field, 'bogus') && problem.status == 422 && ~isempty(strfind(problem.detail, 'unknown field')), ...
      'the problem names the field and says why');
check(~isempty(strfind(message, 'INVALID_FIELD')) && ~isempty(strfind(message, 'bogus')) ...
      && ~isempty(strfind(message, 'HTTP 422')), ['the message carries code, field and status: ' message]);
[code, ~, problem] = caught(@() manipid_identify(url, ds, struct('free', {{'m2', 'm9'}})));
check(strcmp(code, 'manipid:INVALID_FIELD') && ~isempty(strfind(problem.field, 'free')), ...
      ['an unknown parameter name: INVALID_FIELD at free, got ' problem.field]);
[code, message, problem] = caught(@() manipid_upload(url, 0.001, [0 0; 1 NaN; 2 2]));
check(strcmp(code, 'manipid:INVALID_FIELD') && strcmp(problem.field, 'q[1]') && problem.status == 0, ...
      ['NaN is refused before sending, field q[1]: ' message]);
[code, ~, problem] = caught(@() manipid_upload(url, [0 1 2], [0 0; 1 1; 2 2], [1 2 3]));
check(strcmp(code, 'manipid:INVALID_FIELD') && strcmp(problem.field, 'tau'), 'tau of the wrong size is refused');
[code, ~, problem] = caught(@() manipid_upload(url, [0 1 2 3], [0 1 2; 0 1 2]));
check(strcmp(code, 'manipid:INVALID_FIELD') && strcmp(problem.field, 't'), 't that does not match the rows of q is refused');
[code, ~, problem] = caught(@() manipid_result(url, 'job_0000000000000000'));
check(strcmp(code, 'manipid:NOT_FOUND') && problem.status == 404, 'an unknown job: manipid:NOT_FOUND (404)');
[code, ~, problem] = caught(@() manipid_job(url, 'job/../../x'));
check(strcmp(code, 'manipid:INVALID_FIELD') && problem.status == 0, 'a malformed id is refused before sending');
[code, ~, problem] = caught(@() manipid_job('http://127.0.0.1:9', 'job_x'));
check(strcmp(code, 'manipid:CONNECTION'), ['no server: manipid:CONNECTION, got ' code]);
if strcmp(getenv('MANIPID_TEST_TOKEN'), '1')
  [code, ~, problem] = caught(@() manipid_job(struct('url', url, 'token', 'wrong'), job));
  check(strcmp(code, 'manipid:UNAUTHORIZED') && problem.status == 401, 'a wrong token: manipid:UNAUTHORIZED');
end
passed = passed + 1;

% --- URDF robots (when run_tests.sh made the data).
urdf_file = getenv('MANIPID_URDF');
robot_dir = getenv('MANIPID_ROBOT_DIR');
if ~isempty(urdf_file) && ~isempty(robot_dir)
  passed = passed + robot_tests(url, urdf_file, robot_dir, getenv('MANIPID_UR5'), job);
end

fprintf('run_tests: %d groups passed in %.1f s\n', passed, toc(started));
end

function passed = robot_tests(url, urdf_file, robot_dir, ur5_file, preset_job)
%ROBOT_TESTS  The URDF robot functions; returns the number of groups passed.
passed = 0;
document = fileread(urdf_file);
truth = jsondecode(fileread(fullfile(robot_dir, 'truth.json')));

% Upload: the document back byte for byte, the same key twice is one robot, name and tip.
key = sprintf('octave-robot-%d', round(rand() * 1e9));
rb = manipid_upload_robot(url, urdf_file, 'Name', 'octave arm', 'IdempotencyKey', key);
check(strncmp(rb.id, 'rb_', 3) && strcmp(rb.name, 'octave arm') && strcmp(rb.robot_name, 'panda_like'), ...
      'manipid_upload_robot: id rb_..., the name given, the URDF''s robot name');
check(numel(rb.joints) == 7 && isequal(rb.joint_names, arrayfun(@(k) sprintf('panda_joint%d', k), 1:7, 'UniformOutput', false)), ...
      'the robot has the 7 joints panda_joint1..7, in order');
check(rb.parameters.urdf_values.m3 == 2.5 && strcmp(rb.parameters.names{1}, 'm1'), 'the URDF''s values by name');
again = manipid_upload_robot(url, urdf_file, 'Name', 'octave arm', 'IdempotencyKey', key);
check(strcmp(again.id, rb.id), 'the same Idempotency-Key returns the first robot');
[back, text] = manipid_robot(url, rb);
check(strcmp(back.id, rb.id) && isequal(back.joint_names, rb.joint_names), 'manipid_robot gives the robot back');
check(strcmp(text, document), 'manipid_robot gives the URDF back byte for byte');
short = manipid_upload_robot(url, document, 'Name', 'six & more', 'Tip', 'panda_link6');
check(strcmp(short.name, 'six & more') && numel(short.joints) == 6 && strcmp(short.tip_link, 'panda_link6'), ...
      'the document as text, a name with & and space, the chain cut at Tip');
passed = passed + 1;

% Identification: a run (q, qd, qdd, tau) and a validation run; the result by name.
M = dlmread(fullfile(robot_dir, 'run.csv'), ',', 1, 0);
C = dlmread(fullfile(robot_dir, 'check.csv'), ',', 1, 0);
check(size(M, 2) == 29, 'run.csv: t, q1..q7, qd1..qd7, qdd1..qdd7, tau1..tau7');
ds = manipid_upload(url, M(:, 1), M(:, 2:8), M(:, 23:29), [], 'robot run', 'qd', M(:, 9:15), 'qdd', M(:, 16:22));
check(ds.joints == 7 && ds.samples == size(M, 1) && ds.has_rates && ds.has_accelerations && ds.has_torque, ...
      'manipid_upload with qd and qdd: 7 joints, rates, accelerations, torques');
[~, ds_back] = manipid_dataset(url, ds);
check(isequal(ds_back.qd, M(:, 9:15)) && isequal(ds_back.qdd, M(:, 16:22)) && isequal(ds_back.tau, M(:, 23:29)), ...
      'manipid_dataset gives qd, qdd and tau back bit for bit');
chk = manipid_upload(url, C(:, 1), C(:, 2:8), C(:, 23:29), [], 'robot check');
job = manipid_identify(url, ds, 'Robot', rb, 'Friction', 'viscous,coulomb,offset', 'Validate', chk);
check(strcmp(job.kind, 'robot_identification') && strcmp(job.robot_id, rb.id) ...
      && strcmp(job.request.validation_dataset_id, chk.id) ...
      && isequal(job.request.friction, {'viscous'; 'coulomb'; 'offset'}), ...
      'manipid_identify with Robot, Friction and Validate sends a robot identification');
job = manipid_wait(url, job, 300, 'Quiet', true);
r = manipid_result(url, job);
fv2 = r.base_values(strcmp(r.base_names, 'fv2'));
fc2 = r.base_values(strcmp(r.base_names, 'fc2'));
check(abs(fv2 - truth.fv2) < 0.01 && abs(fc2 - truth.fc2) < 0.01, ...
      sprintf('base parameters by name: fv2 = %.4f (truth %.1f), fc2 = %.4f (truth %.1f)', fv2, truth.fv2, fc2, truth.fc2));
check(numel(r.base_names) == numel(r.base_values) && numel(r.base_std) == numel(r.base_values) ...
      && all(r.base_std(~isnan(r.base_std)) > 0) && any(strncmp(r.base_names, 'my2 - 0.316*m3', 14)), ...
      'base_names, base_values and base_std line up; combinations keep their names');
check(numel(r.friction) == 7 && strcmp(r.friction(2).joint, 'panda_joint2') && r.friction(2).fv == fv2 ...
      && ~isnan(r.friction(3).fo) && isnan(r.friction(3).Ia), 'friction per joint by name (no armature: Ia NaN)');
check(r.point.fv2 == fv2 && r.prior.m3 == 2.5 && isequal(size(r.correlation), [numel(r.base_names) numel(r.base_names)]), ...
      'point and prior by name, the correlation matrix');
check(isequal(size(r.validation.relative_error), [1 7]) ...
      && r.validation.overall_relative_error < r.validation.prior.overall_relative_error / 5, ...
      sprintf('validation: %.3g of the torque, the URDF''s own values %.3g', ...
              r.validation.overall_relative_error, r.validation.prior.overall_relative_error));
passed = passed + 1;

% A payload: the tool on the tip link, on the arm as identified above (its truth: tool.json).
T = dlmread(fullfile(robot_dir, 'tool.csv'), ',', 1, 0);
tool = jsondecode(fileread(fullfile(robot_dir, 'tool.json')));
tds = manipid_upload(url, T(:, 1), T(:, 2:8), T(:, 23:29), [], 'tool run');
pj = manipid_identify_payload(url, tds, rb, 'Arm', job, 'Validate', tds, 'JudgeTrim', 0.25, 'Physical', true);
check(strcmp(pj.kind, 'payload_identification') && strcmp(pj.robot_id, rb.id) && pj.request.payload ...
      && strcmp(pj.request.arm_job_id, job.id) && pj.request.judge_trim == 0.25 && pj.request.physical, ...
      'manipid_identify_payload sends a payload identification with the arm and the options by their names');
p = manipid_result(url, manipid_wait(url, pj, 300, 'Quiet', true));
com = reshape(tool.centre_of_mass, 1, 3);
check(p.detected && abs(p.mass - tool.mass) < 0.03 * tool.mass && norm(p.centre_of_mass - com) < 5e-3, ...
      sprintf('the payload: %.4f +- %.2g kg (truth %.2f) at [%.4f %.4f %.4f] m', p.mass, p.mass_std_error, tool.mass, ...
              p.centre_of_mass));
check(isequal(size(p.inertia), [3 3]) && isequal(p.inertia, p.inertia') && isequal(size(p.centre_of_mass_std_errors), [1 3]) ...
      && numel(p.parameter_names) == 10 && strcmp(p.parameter_names{1}, 'm') && p.parameter_values(1) == p.mass, ...
      'the inertia as a symmetric 3-by-3, the ten parameters by name');
check(p.consistent && isstruct(p.physical) && iscell(p.consistency_findings), 'a real rigid body, as asked (Physical)');
check(p.validation.with_payload.overall_relative_error < p.validation.arm_only.overall_relative_error / 2, ...
      'the run is predicted better with the payload than without it');
payload_urdf = manipid_identified_urdf(url, pj);
check(~isempty(strfind(payload_urdf, '<link name="manipid_payload"')), 'the URDF with the payload mounted on the tip link');
[code, ~, problem] = caught(@() manipid_identify_payload(url, tds, rb, 'Arm', preset_job));
check(strcmp(code, 'manipid:INVALID_FIELD') && strcmp(problem.field, 'arm_job_id') && problem.status == 422, ...
      ['an arm that is not a robot identification: field arm_job_id: ' problem.detail]);
[code, ~, problem] = caught(@() manipid_identify_payload(url, tds, rb, 'Mass', -1));
check(strcmp(code, 'manipid:INVALID_FIELD') && strcmp(problem.field, 'known_mass'), 'a negative mass: field known_mass');
passed = passed + 1;

% Two runs together, judged at 4 Hz over joints 1..6: the request's arrays stay arrays.
two = manipid_identify(url, {ds, chk}, 'Robot', rb, 'Friction', 'auto', 'JudgeCutoff', 4, 'TorqueJoints', 1:6, ...
                       'Validate', {chk});
check(isequal(two.request.dataset_ids, {ds.id; chk.id}) && isequal(two.request.validation_dataset_ids, {chk.id}) ...
      && strcmp(two.request.friction, 'auto') && two.request.judge_cutoff == 4 && isequal(two.request.torque_joints(:)', 1:6), ...
      'manipid_identify with a cell of runs sends dataset_ids, the judge and the torque joints');
r2 = manipid_result(url, manipid_wait(url, two, 300, 'Quiet', true));
check(r2.runs == 2 && r2.judge.cutoff_hz == 4 && numel(r2.torque_joints) == 6 && isequal(size(r2.validation.relative_error), [1 6]) ...
      && all(r2.base_share >= 0 & r2.base_share <= 1), 'the result: two runs, the judge, six joints, data shares');
passed = passed + 1;

% The identified URDF: the server's document, with the estimate's masses.
file = [tempname() '.urdf'];
cleanup = onCleanup(@() delete(file)); %#ok<NASGU>
urdf = manipid_identified_urdf(url, job, file);
check(strcmp(fileread(file), urdf), 'manipid_identified_urdf writes what it returns to the file');
for k = 1:7
  link = rb.joints(k).link;
  token = regexp(urdf, ['<link name="' link '"[^>]*>\s*<inertial>.*?<mass value="([^"]+)"'], 'tokens', 'once');
  mass = r.point.(sprintf('m%d', k));
  check(~isempty(token) && abs(str2double(token{1}) - mass) <= 1e-12 * max(1, mass), ...
        sprintf('the identified URDF has link %s''s estimated mass %.6g', link, mass));
end
check(abs(r.point.m3 - 2.5) > 1e-3, 'the estimate''s mass, not the URDF''s');
passed = passed + 1;

% Excitation: a job that makes a dataset of t, q, qd, qdd, at rest at both ends.
ex = manipid_design_excitation(url, rb, 'Period', 2, 'Harmonics', 3, 'Duration', 4, 'MaxSeconds', 3, ...
                               'Friction', {'viscous', 'coulomb'}, 'Name', 'octave excitation');
check(strcmp(ex.kind, 'excitation') && strcmp(ex.robot_id, rb.id) && ex.request.period == 2 ...
      && isequal(ex.request.friction, {'viscous'; 'coulomb'}), 'manipid_design_excitation sends the options by their names');
ex = manipid_wait(url, ex, 120, 'Quiet', true);
[meta, trajectory] = manipid_dataset(url, ex);
check(strcmp(meta.name, 'octave excitation') && strcmp(meta.source_job, ex.id) && ex.result.condition_number > 1, ...
      'the excitation made its named dataset');
check(isequal(size(trajectory.q), [4001 7]) && isequal(size(trajectory.qd), [4001 7]) && isequal(size(trajectory.qdd), [4001 7]) ...
      && isempty(trajectory.tau), 'the trajectory: 4001 samples of q, qd, qdd for 7 joints, no torque');
ends = [trajectory.qd([1 end], :), trajectory.qdd([1 end], :)];
check(all(ends(:) == 0), 'at rest at both ends');
lower = arrayfun(@(joint) joint.limits.lower, rb.joints);
upper = arrayfun(@(joint) joint.limits.upper, rb.joints);
check(all(min(trajectory.q) >= lower) && all(max(trajectory.q) <= upper), 'within the URDF''s position limits');
passed = passed + 1;

% Errors.
[code, ~, problem] = caught(@() manipid_identify(url, ds, 'Robot', 'rb_0000000000000000'));
check(strcmp(code, 'manipid:INVALID_FIELD') && strcmp(problem.field, 'robot_id') && problem.status == 422, ...
      'an unknown robot: manipid:INVALID_FIELD, field robot_id');
[code, ~, problem] = caught(@() manipid_robot(url, 'rb_0000000000000000'));
check(strcmp(code, 'manipid:NOT_FOUND') && problem.status == 404, 'manipid_robot of an unknown robot: NOT_FOUND');
[code, ~, problem] = caught(@() manipid_identify(url, ds, struct('method', 'two-stage'), 'Robot', rb));
check(strcmp(code, 'manipid:INVALID_FIELD') && strcmp(problem.field, 'method'), 'a preset option with a robot is refused, naming it');
[code, ~, problem] = caught(@() manipid_identify(url, ds, 'Validate', chk));
check(strcmp(code, 'manipid:INVALID_FIELD') && problem.status == 0, 'Validate without Robot: refused before sending');
[code, ~, problem] = caught(@() manipid_identify(url, ds, 'Robot', rb, 'Colour', 'red'));
check(strcmp(code, 'manipid:INVALID_FIELD') && strcmp(problem.field, 'Colour') && problem.status == 0, 'an unknown option name');
[code, ~, problem] = caught(@() manipid_upload_robot(url, '<robot name="broken"><link name="a"/>'));
check(strcmp(code, 'manipid:INVALID_FIELD') && strcmp(problem.field, 'urdf') && problem.status == 422, ...
      'a document the service cannot read: field urdf');
[code, ~, problem] = caught(@() manipid_identified_urdf(url, preset_job));
check(strcmp(code, 'manipid:CONFLICT') && problem.status == 409, 'the identified URDF of a preset job: CONFLICT');
if ~isempty(ur5_file)
  ur5 = manipid_upload_robot(url, ur5_file);
  [code, ~, problem] = caught(@() manipid_identify(url, ds, 'Robot', ur5));
  check(strcmp(code, 'manipid:INVALID_FIELD') && strcmp(problem.field, 'dataset_id') ...
        && ~isempty(strfind(problem.detail, '7 joints')), ['a 7-joint run for a 6-joint robot: ' problem.detail]);
end
passed = passed + 1;
end

function check(condition, what)
if ~condition
  error('run_tests:failed', 'FAILED: %s', what);
end
fprintf('ok  %s\n', what);
end

function [identifier, message, problem] = caught(action)
%CAUGHT  Run ACTION; the identifier and message of the error it raised ('' if none).
identifier = '';
message = '';
problem = [];
try
  action();
catch err
  identifier = err.identifier;
  message = err.message;
  problem = manipid_last_problem();
end
end

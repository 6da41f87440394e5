// robots.js — the URDF robots: the list (/robots) with an upload form, and one robot
// (/robots/{id}) with its joints and limits, the jobs that used it, and forms that design an
// excitation for it and identify it from measured runs (CSV files from the disk, or stored datasets).
import { api, ApiProblem, downloadLink } from "./api.js";
import { facts, h, number, plural, section, stateBadge, when } from "./dom.js";
import { jobPath, robotPath } from "./paths.js";

// Jobs looked through for a robot's: the API has no robot_id filter, and a list's jobs carry
// their results (a robot identification's is tens of kB), so only the newest.
const JOB_SCAN = 100;

function field(label, input, hint) {
  return h("div", { class: "field" }, h("label", { for: input.id }, label), input,
    hint ? h("small", { id: `${input.id}-hint` }, hint) : null);
}

function textInput(id, name, value = "", extra = {}) {
  return h("input", { id, name, type: "text", value: String(value), autocomplete: "off", ...extra });
}

/** Shows an API error in `status` and marks the field at fault (by its name attribute). */
function showProblem(form, status, error) {
  status.textContent = error instanceof ApiProblem ? `${error.field ? error.field + ": " : ""}${error.message}` : String(error);
  status.setAttribute("role", "alert");
  const culprit = error.field && form.querySelector(`[name="${CSS.escape(error.field)}"]`);
  if (culprit) { culprit.setAttribute("aria-invalid", "true"); culprit.focus(); }
}

function clearProblems(form, status) {
  form.querySelectorAll("[aria-invalid]").forEach((element) => element.removeAttribute("aria-invalid"));
  status.setAttribute("role", "status");
}

// ---- joints -----------------------------------------------------------------------------------

const UNITS = { revolute: ["rad", "rad/s", "N·m"], continuous: ["rad", "rad/s", "N·m"], prismatic: ["m", "m/s", "N"] };

function range(joint) {
  const [unit] = UNITS[joint.type] || ["", ""];
  const { lower, upper } = joint.limits || {};
  if (joint.type === "continuous" || (lower == null && upper == null)) return "no limits";
  return `${number(lower, 4)} … ${number(upper, 4)} ${unit}`;
}

function limit(value, unit) {
  return value === null || value === undefined ? "none" : `${number(value, 4)} ${unit}`;
}

function jointsTable(robot, { id, full }) {
  const head = full
    ? ["#", "Joint", "Link", "Type", "Axis", "Position", "Velocity", "Effort", "Damping", "Friction"]
    : ["Joint", "Type", "Position", "Velocity", "Effort"];
  return h("table", { id, class: `data${full ? "" : " compact"}` },
    full ? h("caption", {}, "The moving joints from the base; parameter names end in their number (m1, fv1, …)") : null,
    h("thead", {}, h("tr", {}, head.map((label) => h("th", { scope: "col", class: ["#", "Damping", "Friction"].includes(label) ? "number" : null }, label)))),
    h("tbody", {}, robot.joints.map((joint, k) => {
      const [, rate, force] = UNITS[joint.type] || ["", "", ""];
      return h("tr", { dataset: { joint: joint.name } },
        full ? h("td", { class: "number" }, String(k + 1)) : null,
        h("th", { scope: "row" }, joint.name),
        full ? h("td", {}, joint.link) : null,
        h("td", {}, joint.type),
        full ? h("td", {}, `(${(joint.axis || []).map((value) => number(value, 3)).join(", ")})`) : null,
        h("td", {}, range(joint)),
        h("td", {}, limit(joint.limits?.velocity, rate)),
        h("td", {}, limit(joint.limits?.effort, force)),
        full ? h("td", { class: "number" }, number(joint.damping, 4)) : null,
        full ? h("td", { class: "number" }, number(joint.friction, 4)) : null);
    })));
}

const FRICTION_NAMES = { viscous: "viscous", coulomb: "Coulomb", offset: "offset" };

/** "with viscous and Coulomb friction", or "" without friction. */
function frictionNote(robot) {
  const friction = (robot.base_parameters?.friction || []).map((term) => FRICTION_NAMES[term] || term);
  return friction.length ? `with ${friction.join(" and ")} friction` : "";
}

function baseCount(robot) {
  const note = frictionNote(robot);
  return `${robot.base_parameters?.count ?? "–"}${note ? ` (${note})` : ""}`;
}

// ---- the list ----------------------------------------------------------------------------------

function robotRow(robot) {
  const joints = robot.joints.length;
  return h("tr", { dataset: { robotId: robot.id, joints: String(joints), baseParameters: String(robot.base_parameters?.count) } },
    h("th", { scope: "row" }, h("a", { href: robotPath(robot.id) }, robot.name),
      robot.robot_name && robot.robot_name !== robot.name ? h("div", { class: "muted" }, `URDF: ${robot.robot_name}`) : null),
    h("td", {}, h("code", {}, robot.id)),
    h("td", { class: "joints-cell" },
      h("details", {}, h("summary", {}, `${plural(joints, "joint")}: ${robot.base_link} → ${robot.tip_link}`),
        h("div", { class: "scroll" }, jointsTable(robot, { id: `joints-${robot.id}`, full: false })))),
    h("td", { class: "number" }, String(robot.base_parameters?.count ?? "–"),
      frictionNote(robot) ? h("div", { class: "muted small" }, frictionNote(robot)) : null),
    h("td", {}, when(robot.created_at)));
}

function uploadForm(navigate) {
  const file = h("input", { id: "u-file", name: "urdf", type: "file", accept: ".urdf,.xml,application/xml,text/xml", required: true });
  const status = h("p", { class: "form-status", role: "status", "aria-live": "polite" });
  const form = h("form", { id: "robot-upload", class: "card", "aria-labelledby": "robot-upload-title", novalidate: true },
    h("h2", { id: "robot-upload-title" }, "Upload a URDF"),
    h("p", { class: "muted" }, "A serial arm: the chain runs from the base link (default the root) to the tip (default the only leaf); " +
      "fixed joints are merged. At most 4 MiB."),
    h("div", { class: "fields" },
      field("URDF file", file),
      field("Name", textInput("u-name", "name", "", { placeholder: "the URDF's robot name" })),
      field("Base link", textInput("u-base", "base", "", { placeholder: "the root" })),
      field("Tip link", textInput("u-tip", "tip", "", { placeholder: "the only leaf" }))),
    h("div", { class: "actions" }, h("button", { type: "submit", id: "robot-upload-submit" }, "Upload"), status));
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    clearProblems(form, status);
    const chosen = file.files[0];
    if (!chosen) {
      status.textContent = "Choose a URDF file first.";
      file.setAttribute("aria-invalid", "true");
      file.focus();
      return;
    }
    const body = { urdf: await chosen.text() };
    for (const name of ["name", "base", "tip"]) {
      const value = form.querySelector(`[name=${name}]`).value.trim();
      if (value) body[name] = value;
    }
    status.textContent = "Uploading…";
    try {
      const robot = await api("/v1/robots", { method: "POST", body });
      navigate(robotPath(robot.id));
    } catch (error) {
      showProblem(form, status, error);
    }
  });
  return form;
}

export async function robotsListView(main, navigate) {
  const body = h("tbody");
  const more = h("button", { type: "button", id: "robots-more", hidden: true }, "Older robots");
  main.replaceChildren(
    h("h1", {}, "Robots"),
    section("robots-section", "URDF robots",
      h("div", { class: "scroll" }, h("table", { id: "robots", class: "data" },
        h("caption", {}, "Newest first; open a robot for its limits, jobs and forms"),
        h("thead", {}, h("tr", {}, ["Robot", "ID", "Joints", "Base parameters", "Created"].map((label) => h("th", { scope: "col" }, label)))),
        body)),
      more),
    uploadForm(navigate));
  document.title = "Robots · manipid";
  document.body.dataset.ready = "false";
  let token = null;
  const load = async () => {
    const page = await api(`/v1/robots${token ? `?page_token=${encodeURIComponent(token)}` : ""}`);
    body.append(...page.items.map(robotRow));
    if (!body.children.length) body.append(h("tr", {}, h("td", { colspan: 5, class: "muted" }, "No robots yet: upload a URDF below.")));
    token = page.next_page_token || null;
    more.hidden = !token;
  };
  more.addEventListener("click", load);
  await load();
  document.body.dataset.ready = "true";
}

// ---- one robot ----------------------------------------------------------------------------------

async function robotJobs(id) {
  const page = await api(`/v1/jobs?robot_id=${encodeURIComponent(id)}&page_size=${JOB_SCAN}`);
  return { jobs: page.items, complete: !page.next_page_token };
}

function jobsSection({ jobs, complete }) {
  const rows = jobs.map((job) => {
    const result = job.result || {};
    const figure = job.kind === "excitation" ? `condition number ${number(result.condition_number, 4)}`
      : result.fit ? `fit error ${number(100 * result.fit.overall_relative_error, 3)} %` : "–";
    return h("tr", { dataset: { jobId: job.id } },
      h("td", {}, h("a", { href: jobPath(job.id) }, job.id)), h("td", {}, job.kind), h("td", {}, stateBadge(job.state)),
      h("td", {}, when(job.created_at)), h("td", {}, job.state === "succeeded" ? figure : "–"));
  });
  return section("robot-jobs", "Jobs on this robot",
    complete ? null : h("p", { class: "muted" }, `The ${JOB_SCAN} newest of them.`),
    rows.length
      ? h("div", { class: "scroll" }, h("table", { id: "robot-jobs-table", class: "data" },
          h("thead", {}, h("tr", {}, ["Job", "Kind", "State", "Created", "Result"].map((label) => h("th", { scope: "col" }, label)))),
          h("tbody", {}, rows)))
      : h("p", {}, "None yet: design an excitation below, or identify from a run."));
}

function checkbox(id, name, value, label, checked) {
  return h("span", { class: "check" }, h("input", { id, name, value, type: "checkbox", checked }), h("label", { for: id }, ` ${label}`));
}

function excitationForm(robot, navigate) {
  const status = h("p", { class: "form-status", role: "status", "aria-live": "polite" });
  const form = h("form", { id: "excitation-form", class: "card", "aria-labelledby": "excitation-form-title", novalidate: true },
    h("h2", { id: "excitation-form-title" }, "Design an excitation"),
    h("p", { class: "muted" }, "Fourier-series joint trajectories that start and end at rest, stay within the URDF's position, " +
      "velocity and effort limits (and those given here), and make the base regressor as well conditioned as the evaluation budget allows. " +
      "Limits: one value for every joint, or one per joint separated by commas."),
    h("div", { class: "fields" },
      field("Period, s", textInput("e-period", "period", 10, { inputmode: "decimal" })),
      field("Harmonics", textInput("e-harmonics", "harmonics", 5, { inputmode: "numeric" })),
      field("Duration, s", textInput("e-duration", "duration", "", { inputmode: "decimal", placeholder: "one period" })),
      field("Max velocity, rad/s", textInput("e-max-velocity", "max_velocity", "", { inputmode: "decimal", placeholder: "the URDF's" })),
      field("Max acceleration, rad/s²", textInput("e-max-acceleration", "max_acceleration", "", { inputmode: "decimal", placeholder: "7.5" })),
      field("Max jerk, rad/s³", textInput("e-max-jerk", "max_jerk", "", { inputmode: "decimal", placeholder: "none" })),
      field("Max torque, N·m", textInput("e-max-torque", "max_torque", "", { inputmode: "decimal", placeholder: "the URDF's efforts" })),
      field("Position margin, rad", textInput("e-position-margin", "position_margin", "", { inputmode: "decimal", placeholder: "0.1" })),
      field("Start pose, rad", textInput("e-start-pose", "start_pose", "", { placeholder: "none: q1,…,qn" }),
            "where the arm stands: the run ramps from it and back"),
      field("Criterion", h("select", { id: "e-criterion", name: "criterion" },
        h("option", { value: "condition" }, "condition number"), h("option", { value: "logdet" }, "log det"))),
      field("Evaluations", textInput("e-max-evaluations", "max_evaluations", 8000, { inputmode: "numeric" }),
            "the budget: the same on every machine"),
      field("Time cap, s", textInput("e-max-seconds", "max_seconds", 300, { inputmode: "decimal" })),
      field("Seed", textInput("e-seed", "seed", 1, { inputmode: "numeric" }))),
    h("div", { class: "actions" }, h("button", { type: "submit", id: "excitation-submit" }, "Design"), status));
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    clearProblems(form, status);
    const body = { robot_id: robot.id, criterion: form.querySelector("[name=criterion]").value };
    for (const name of ["period", "harmonics", "duration", "position_margin", "max_evaluations", "max_seconds", "seed"]) {
      const value = form.querySelector(`[name=${name}]`).value.trim();
      if (value) body[name] = Number(value);
    }
    // One value, or a comma-separated list (one per joint); the server names what is wrong with either.
    const list = (text) => text.split(",").map((item) => Number(item.trim()));
    for (const name of ["max_velocity", "max_acceleration", "max_jerk", "max_torque"]) {
      const value = form.querySelector(`[name=${name}]`).value.trim();
      if (value) body[name] = value.includes(",") ? list(value) : Number(value);
    }
    const pose = form.querySelector("[name=start_pose]").value.trim();
    if (pose) body.start_pose = list(pose);
    status.textContent = "Submitting…";
    try {
      const job = await api("/v1/excitations", { method: "POST", body });
      navigate(jobPath(job.id));
    } catch (error) {
      showProblem(form, status, error);
    }
  });
  return form;
}

// ---- identify ------------------------------------------------------------------------------------

// What each run is for: the role column of the identify form's run table.
const ROLES = [["train", "training"], ["validation", "validation (held out)"], ["unused", "not used"]];

/** A <select> of [value, label] pairs (or plain values). */
function choices(id, name, options, attributes = {}) {
  return h("select", { id, name, ...attributes },
    options.map((option) => (Array.isArray(option) ? h("option", { value: option[0] }, option[1]) : h("option", { value: option }, option))));
}

/** "columns: no column named q1 …" — an API problem in one line. */
function problemText(error) {
  return error instanceof ApiProblem ? `${error.field ? error.field + ": " : ""}${error.message}` : String(error.message || error);
}

/** The seconds a dataset spans (its samples at its period), or "–". */
function duration(dataset) {
  return typeof dataset.dt === "number" && dataset.samples > 0 ? number((dataset.samples - 1) * dataset.dt, 4) : "–";
}

/**
 * The identify form: the runs to identify from — CSV files from the user's disk, uploaded when the
 * form is sent (POST /v1/datasets?name=<file name>, with the column map and units when given), and
 * the stored datasets with this robot's joints and torque — each named a training run, a validation
 * run (held out: the estimate predicts it) or not used; at least one training run. Then the friction
 * terms, armature and physical consistency.
 */
async function identifyForm(robot, navigate) {
  const n = robot.joints.length;
  const page = await api("/v1/datasets?page_size=1000");
  const fits = (dataset) => dataset.joints === n && dataset.has_torque;
  const status = h("p", { class: "form-status", role: "status", "aria-live": "polite" });
  const files = h("input", { id: "i-files", name: "files", type: "file", multiple: true, accept: ".csv,text/csv" });
  const columns = textInput("i-columns", "columns", "", { placeholder: "time=t,position_{j}=q{j},effort_{j}=tau{j}", spellcheck: "false",
                                                          "aria-describedby": "i-columns-hint" });
  const format = h("details", { id: "i-format" },
    h("summary", {}, "Columns and units, for files that are not t, q1…, tau1… in s and rad"),
    h("div", { class: "fields" },
      field("Column map", columns, ["FILE=MANIPID rules: ", h("code", {}, "{j}"), " a joint number, ",
                                    h("code", {}, "{joint}"), " one of this robot's joint names"]),
      field("Time unit", choices("i-time-unit", "time_unit", ["s", "ms", "us", "ns"])),
      field("Angle unit", choices("i-angle-unit", "angle_unit", [["rad", "rad"], ["deg", "degrees"]]), "of q (and qd, qdd, ref)")));
  const tbody = h("tbody");
  const runs = [];  // in table order: {row, role (its select), file?, dataset?, touched, cells}
  let serial = 0;

  const setStatus = (run, text, bad = false) => {
    run.statusCell.replaceChildren(bad ? h("span", { class: "flag" }, text) : text);
    if (bad) run.row.dataset.refused = "true"; else delete run.row.dataset.refused;
  };
  const stored = (run, dataset) => {
    run.dataset = dataset;
    run.row.dataset.datasetId = dataset.id;
    run.samplesCell.textContent = String(dataset.samples);
    run.spanCell.textContent = duration(dataset);
    run.idCell.replaceChildren(h("code", {}, dataset.id));
  };
  const newRun = ({ dataset, file, role }) => {
    serial += 1;
    const name = dataset ? dataset.name || dataset.id : file.name;
    const select = choices(`i-role-${serial}`, "role", ROLES, { class: "role", "aria-label": `Role of ${name}` });
    select.value = role;
    const run = { role: select, file, touched: false, idCell: h("div", { class: "muted small" }, "from your disk"),
                  samplesCell: h("td", { class: "number" }, "–"), spanCell: h("td", { class: "number" }, "–"), statusCell: h("td", { class: "run-status" }) };
    select.addEventListener("change", () => { run.touched = true; select.removeAttribute("aria-invalid"); });
    run.row = h("tr", { dataset: file ? { file: file.name } : {} },
      h("th", { scope: "row" }, h("span", { class: "run-name" }, name), run.idCell),
      h("td", {}, select), run.samplesCell, run.spanCell, run.statusCell);
    if (dataset) {
      stored(run, dataset);
      setStatus(run, `stored ${when(dataset.created_at)}`);
    } else {
      setStatus(run, "uploaded on Identify");
    }
    return run;
  };
  const render = () => tbody.replaceChildren(...(runs.length ? runs.map((run) => run.row)
    : [h("tr", {}, h("td", { colspan: 5, class: "muted" }, `No runs with ${n} joints and torque yet: add CSV files above.`))]));

  // The stored runs, newest first: the newest trains and the next one validates.
  page.items.filter(fits).forEach((dataset, i) => runs.push(newRun({ dataset, role: i === 0 ? "train" : i === 1 ? "validation" : "unused" })));
  render();

  // Files from the disk go first in the table. They become the runs: the stored runs whose role
  // nobody chose are set to "not used", the first file trains, the second validates, more train.
  files.addEventListener("change", () => {
    const known = (file) => runs.some((run) => run.file && !run.dataset && run.file.name === file.name &&
                                               run.file.size === file.size && run.file.lastModified === file.lastModified);
    const chosen = [...files.files].filter((file) => !known(file));
    files.value = "";
    if (!chosen.length) return;
    for (const run of runs) if (!run.touched && !run.file) run.role.value = "unused";
    let train = runs.some((run) => run.role.value === "train"), validation = runs.some((run) => run.role.value === "validation");
    const added = chosen.map((file) => {
      const role = !train ? "train" : !validation ? "validation" : "train";
      if (role === "train") train = true; else validation = true;
      return newRun({ file, role });
    });
    runs.unshift(...added);
    render();
    clearProblems(form, status);
    status.textContent = `Added ${added.map((run) => run.file.name).join(", ")}: ${plural(added.length, "file")} to upload on Identify.`;
  });

  const submit = h("button", { type: "submit", id: "identify-submit" }, "Identify");
  const form = h("form", { id: "identify-form", class: "card", "aria-labelledby": "identify-form-title", novalidate: true },
    h("h2", { id: "identify-form-title" }, "Identify"),
    h("p", { class: "muted" }, `The base parameters from measured runs of this robot: CSV logs of t, q1…q${n} and tau1…tau${n} ` +
      "(or any columns, mapped below). Training runs are fitted together; validation runs are held out, and the page of the " +
      "result shows how well the estimate predicts them beside the URDF's own values."),
    h("div", { class: "runs-files" },
      field("Add CSV files", files, "one or more runs; each is uploaded as a dataset named after its file"),
      format),
    h("h3", { id: "i-runs-title" }, "Runs"),
    h("p", { class: "muted", id: "i-runs-note" }, `The files added and the stored datasets with ${n} joints and torque, ` +
      "each used as a training run, a validation run or not at all. At least one training run."),
    h("div", { class: "scroll" }, h("table", { id: "i-runs", class: "data runs", "aria-labelledby": "i-runs-title",
                                                "aria-describedby": "i-runs-note" },
      h("thead", {}, h("tr", {}, ["Run", "Use as", "Samples", "Duration, s", "Status"].map((label, i) =>
        h("th", { scope: "col", class: i === 2 || i === 3 ? "number" : null }, label)))),
      tbody)),
    h("fieldset", {}, h("legend", {}, "Estimate also"),
      checkbox("i-viscous", "friction", "viscous", "viscous friction fv", true),
      checkbox("i-coulomb", "friction", "coulomb", "Coulomb friction fc", true),
      checkbox("i-offset", "friction", "offset", "torque offset fo", false),
      checkbox("i-armature", "armature", "true", "rotor inertia Ia", false),
      checkbox("i-physical", "physical", "true", "physically consistent (every link a rigid body, friction ≥ 0)", false)),
    h("div", { class: "actions" }, submit, status));

  /** The run an identification problem names (dataset_ids[1], validation_dataset_id), if any. */
  const runNamed = (field, training, validating) => {
    const match = /^(validation_)?dataset_ids?(?:\[(\d+)\])?$/.exec(field || "");
    return match ? (match[1] ? validating : training)[Number(match[2] || 0)] : undefined;
  };
  const uploadPath = (file) => {
    const query = new URLSearchParams({ name: file.name });
    const map = columns.value.trim();
    if (map) {
      query.set("columns", map);
      query.set("robot_id", robot.id);  // what {joint} rules match: this robot's joint names
    }
    for (const name of ["time_unit", "angle_unit"]) {
      const value = form.querySelector(`[name=${name}]`).value;
      if (value !== "s" && value !== "rad") query.set(name, value);
    }
    return `/v1/datasets?${query}`;
  };

  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    clearProblems(form, status);
    const training = runs.filter((run) => run.role.value === "train");
    if (!training.length) {
      status.textContent = runs.length ? "Choose at least one training run (Use as: training)." : "Add at least one CSV file: a run to identify from.";
      status.setAttribute("role", "alert");
      const culprit = runs.length ? runs[0].role : files;
      culprit.setAttribute("aria-invalid", "true");
      culprit.focus();
      return;
    }
    submit.disabled = true;
    try {
      // Upload the files that are used, one by one; each refusal is named by its file.
      const refused = [];
      for (const run of runs.filter((each) => each.file && !each.dataset && each.role.value !== "unused")) {
        setStatus(run, "uploading…");
        status.textContent = `Uploading ${run.file.name}…`;
        try {
          stored(run, await api(uploadPath(run.file), { method: "POST", body: run.file, type: "text/csv" }));
          if (fits(run.dataset)) {
            setStatus(run, "uploaded");
          } else {
            const why = run.dataset.joints !== n ? `${plural(run.dataset.joints, "joint")}, the robot has ${n}` : "no torque columns";
            setStatus(run, `stored, but ${why}: not a run of this robot`, true);
            run.role.setAttribute("aria-invalid", "true");
            refused.push(run.file.name);
          }
        } catch (error) {
          setStatus(run, `refused: ${problemText(error)}`, true);
          refused.push(run.file.name);
          const culprit = error.field && form.querySelector(`[name="${CSS.escape(error.field)}"]`);
          if (culprit) { culprit.setAttribute("aria-invalid", "true"); culprit.closest("details")?.setAttribute("open", ""); }
        }
      }
      if (refused.length) {
        const names = refused.length === 1 ? refused[0] : `${refused.slice(0, -1).join(", ")} and ${refused.at(-1)}`;
        status.textContent = `Not identified: ${names} ${refused.length === 1 ? "was" : "were"} not usable; ` +
          `${refused.length === 1 ? "its row says" : "their rows say"} why.`;
        status.setAttribute("role", "alert");
        return;
      }
      const validating = runs.filter((run) => run.role.value === "validation");
      const body = {
        robot_id: robot.id,
        dataset_ids: training.map((run) => run.dataset.id),
        friction: [...form.querySelectorAll("input[name=friction]:checked")].map((box) => box.value),
      };
      if (validating.length) body.validation_dataset_ids = validating.map((run) => run.dataset.id);
      if (form.querySelector("[name=armature]").checked) body.armature = true;
      if (form.querySelector("[name=physical]").checked) body.physical = true;
      status.textContent = "Submitting…";
      try {
        const job = await api("/v1/identifications", { method: "POST", body });
        navigate(jobPath(job.id));
      } catch (error) {
        const run = runNamed(error.field, training, validating);
        if (!run) { showProblem(form, status, error); return; }
        status.textContent = `${run.file?.name || run.dataset.name || run.dataset.id}: ${problemText(error)}`;
        status.setAttribute("role", "alert");
        run.role.setAttribute("aria-invalid", "true");
        run.role.focus();
      }
    } finally {
      submit.disabled = false;
    }
  });
  return form;
}

export async function robotView(main, id, navigate) {
  const robot = await api(`/v1/robots/${id}`);
  document.title = `${robot.name} · manipid`;
  document.body.dataset.ready = "false";
  const names = robot.parameters?.names || [];
  main.replaceChildren(h("article", { id: "robot", dataset: { robotId: robot.id } },
    h("p", { class: "crumbs" }, h("a", { href: "/robots" }, "Robots"), " / "),
    h("h1", {}, robot.name),
    h("div", { class: "card" },
      facts([
        ["ID", h("code", {}, robot.id)],
        ["URDF robot", robot.robot_name],
        ["Chain", `${robot.base_link} → ${robot.tip_link}, ${plural(robot.joints.length, "moving joint")}`],
        ["Gravity", `(${(robot.gravity || []).map((value) => number(value, 4)).join(", ")}) m/s² in ${robot.base_link}'s frame`],
        ["Parameters", `${names.length} standard (10 per body, then friction per joint); base: ${baseCount(robot)}`],
        ["Created", when(robot.created_at)],
        ["URDF", downloadLink(`/v1/robots/${robot.id}?format=urdf`, "the document as uploaded", { id: "robot-urdf" })],
        ["API", h("a", { href: `/v1/robots/${robot.id}` }, "robot JSON")],
      ]),
      robot.warnings?.length ? [h("h3", {}, "Warnings"), h("ul", { class: "warnings" }, robot.warnings.map((text) => h("li", {}, text)))] : null),
    section("robot-joints-section", "Joints", h("div", { class: "scroll" }, jointsTable(robot, { id: "robot-joints", full: true })))));
  const article = main.querySelector("#robot");
  const [jobs, identify] = await Promise.all([robotJobs(robot.id), identifyForm(robot, navigate)]);
  article.append(jobsSection(jobs), excitationForm(robot, navigate), identify);
  document.body.dataset.ready = "true";
}

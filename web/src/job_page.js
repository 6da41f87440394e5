// job_page.js — one job at its own address, /jobs/{id}: state and progress; for an
// identification the cost over evaluations (log scale) and each parameter's estimate over
// evaluations beside its true value when known (simulated here, or given as truth) (the paper's Figs. 4–5),
// live while it runs; then the result table, correlation heat map, identifiability findings,
// and the filtered measured torque beside the model torque at the estimate with the residual;
// for every job with data, the measured angles (with the reference) and torques (Fig. 2).
// A job on a URDF robot (a robot_identification, a payload_identification or an excitation) shares the
// header, the live state and Cancel; its sections are robot_job.js's (payload_job.js's for a payload).
import { api } from "./api.js";
import { lineChart, positive, PALETTE } from "./charts.js";
import { h, number, section, stateBadge, when } from "./dom.js";
import { robotPath } from "./paths.js";
import { payloadSections } from "./payload_job.js";
import { excitationSections, robotIdentificationSections } from "./robot_job.js";

const MAX_POINTS = 2000;  // per series, for drawing; the server keeps every sample and evaluation
const TERMINAL = ["succeeded", "failed", "cancelled"];
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

/** The simulation request behind a job's data, if its data were simulated here. */
async function simulationBehind(job) {
  if (job.kind === "simulation") return job.request;
  if (job.request.simulation) return job.request.simulation;
  if (!job.dataset_id) return null;
  const dataset = await api(`/v1/datasets/${job.dataset_id}`);
  if (!dataset.source_job) return null;
  const source = await api(`/v1/jobs/${dataset.source_job}`);
  return source.kind === "simulation" ? source.request : source.request.simulation || null;
}

/**
 * The true values, only where they are known: the server's word once the job has a result
 * (result.truth: the user's "truth", else the simulation's parameters, else null), before that
 * the request's "truth" or the simulation behind the data. Uploaded data have none: no preset's
 * values beside another robot's estimates.
 */
async function trueValues(job) {
  if (job.result && "truth" in job.result) return job.result.truth;
  if (job.request.truth) return job.request.truth;
  const simulation = await simulationBehind(job).catch(() => null);
  if (!simulation) return null;
  const energy = simulation.kinetic_energy || "complete";
  const preset = await api(`/v1/presets/${simulation.preset || "cedro2009"}?kinetic_energy=${energy}`);
  return { ...preset.true_parameters, ...(simulation.parameters || {}) };
}

function summaryList(job) {
  const kinds = { robot_identification: "identification of a URDF robot's base parameters",
                  payload_identification: "identification of a payload on a URDF robot's tip link" };
  const kind = kinds[job.kind] || job.kind;
  const rows = [["Kind", kind], ["Created", when(job.created_at)], ["Started", when(job.started_at)],
                ["Finished", when(job.finished_at)]];
  if (job.robot_id) rows.push(["Robot", h("a", { href: robotPath(job.robot_id) }, job.robot_id)]);
  if (job.kind === "identification") {
    rows.push(["Evaluations", String(job.progress.evaluations)], ["Best cost", number(job.progress.best_cost, 6)]);
  }
  if (job.dataset_id) rows.push(["Dataset", h("a", { href: `/v1/datasets/${job.dataset_id}/data?format=csv` }, `${job.dataset_id} (CSV)`)]);
  if (job.validation_dataset_id) {
    rows.push(["Validation dataset", h("a", { href: `/v1/datasets/${job.validation_dataset_id}/data?format=csv` }, `${job.validation_dataset_id} (CSV)`)]);
  }
  rows.push(["API", h("a", { href: `/v1/jobs/${job.id}` }, "job JSON")]);
  return h("dl", { class: "summary" }, rows.map(([term, detail]) => [h("dt", {}, term), h("dd", {}, detail)]));
}

// ---- result -------------------------------------------------------------------------------

/** "m1*l1^2" → the product of the true values, when every factor is known. */
function combinationTruth(name, truth) {
  if (!truth) return null;
  const match = /^m(\d+)\*l(\d+)\^2$/.exec(name);
  if (!match) return null;
  const mass = truth[`m${match[1]}`], length = truth[`l${match[2]}`];
  return mass === undefined || length === undefined ? null : mass * length * length;
}

function resultTable(result, truth) {
  const unidentifiable = new Set(result.identifiability.unidentifiable);
  const free = new Set(result.free);
  const head = ["Parameter", "Initial", "Estimate", "Std error", ...(truth ? ["True", "Error"] : [])];
  const rows = Object.keys(result.estimates).map((name) => {
    const estimate = result.estimates[name];
    const known = truth ? truth[name] : undefined;
    const alone = !unidentifiable.has(name);
    const fixed = !free.has(name);
    return h("tr", { dataset: { parameter: name } },
      h("th", { scope: "row" }, name, fixed ? h("span", { class: "muted" }, " (fixed)") : null),
      h("td", { class: "number" }, number(result.initial[name])),
      h("td", { class: "number", dataset: { estimate: String(estimate) } }, alone ? number(estimate, 7) : "not alone"),
      h("td", { class: "number" }, alone && !fixed ? number(result.std_errors[name], 3) : "–"),
      truth ? h("td", { class: "number" }, number(known)) : null,
      truth ? h("td", { class: "number" }, alone && known ? `${number((100 * (estimate - known)) / known, 3)} %` : "–") : null);
  });
  for (const combination of result.identifiability.combinations) {
    const known = combinationTruth(combination.name, truth);
    rows.push(h("tr", { class: "combination", dataset: { parameter: combination.name } },
      h("th", { scope: "row" }, combination.name),
      h("td", {}, ""),
      h("td", { class: "number", dataset: { estimate: String(combination.value) } }, number(combination.value, 7)),
      h("td", { class: "number" }, number(combination.std_error, 3)),
      truth ? h("td", { class: "number" }, number(known)) : null,
      truth ? h("td", { class: "number" }, known ? `${number((100 * (combination.value - known)) / known, 3)} %` : "–") : null));
  }
  return h("div", { class: "scroll" }, h("table", { id: "result-table", class: "data" },
    h("caption", {}, "Estimates (SI units: kg, m); std error from the Gauss–Newton approximation"),
    h("thead", {}, h("tr", {}, head.map((label) => h("th", { scope: "col" }, label)))),
    h("tbody", {}, rows)));
}

function heatColor(value) {
  if (value === null || value === undefined || Number.isNaN(value)) return "#f2f2f2";
  const strength = Math.min(1, Math.abs(value));
  const hue = value >= 0 ? 0 : 220;  // red positive, blue negative
  return `hsl(${hue} 75% ${100 - 45 * strength}%)`;
}

function correlationHeatMap(correlation) {
  // Parameters the data cannot determine alone have no correlations (nulls): leave them out.
  const keep = correlation.parameters.map((_, i) => correlation.matrix[i]?.some((value, j) => j !== i && value !== null));
  const names = correlation.parameters.filter((_, i) => keep[i]);
  const matrix = correlation.matrix.filter((_, i) => keep[i]).map((row) => row.filter((_, j) => keep[j]));
  if (!names.length) return h("p", { class: "muted" }, "No correlations to show.");
  return h("div", { class: "scroll" }, h("table", { id: "correlation", class: "heat" },
    h("caption", {}, "Correlation of the estimates (red +1, blue −1)"),
    h("thead", {}, h("tr", {}, h("td", {}), names.map((name) => h("th", { scope: "col" }, name)))),
    h("tbody", {}, names.map((row, i) => h("tr", {},
      h("th", { scope: "row" }, row),
      names.map((column, j) => {
        const value = matrix[i]?.[j];
        const text = value === null || value === undefined ? "–" : value.toFixed(2);
        return h("td", { style: `background:${heatColor(value)}`, title: `corr(${row}, ${column}) = ${text}` }, text);
      }))))));
}

function resultSection(result, truth) {
  const report = result.identifiability;
  const findings = report.findings.length
    ? h("ul", { id: "findings" }, report.findings.map((finding) => h("li", {}, finding)))
    : h("p", { id: "findings" }, "Every free parameter is determined by the data on its own.");
  const filter = result.filter;
  const facts = [
    ["Method", `${result.method}, ${result.algorithm}`],
    ["Stopped", `${result.stop_reason} after ${result.evaluations} evaluations in ${number(result.wall_seconds, 3)} s`],
    ["Cost", `${number(result.initial_cost, 4)} → ${number(result.final_cost, 6)}`],
    ...(result.method === "output-error"
      ? [["Compared", "simulated and measured joint angles (no filter)"]]
      : [["Filter", `M = ${filter.half_length}, Ωg = ${number(filter.band, 4)} rad/sample${filter.automatic ? " (chosen from the data)" : ""}`],
         ["Torque", result.torque_source]]),
  ];
  return section("result", "Result",
    h("dl", { class: "summary" }, facts.map(([term, detail]) => [h("dt", {}, term), h("dd", {}, detail)])),
    resultTable(result, truth),
    h("h3", {}, "Identifiability"), findings,
    result.warnings.length ? [h("h3", {}, "Warnings"), h("ul", { class: "warnings" }, result.warnings.map((w) => h("li", {}, w)))] : null,
    h("h3", {}, "Correlation"), correlationHeatMap(result.correlation));
}

// ---- charts -------------------------------------------------------------------------------

class HistoryCharts {
  constructor(parent, names, truth) {
    this.names = names;
    this.truth = truth;
    this.costBox = h("div", { id: "chart-cost" });
    this.parameterBoxes = Object.fromEntries(names.map((name) => [name, h("div", { id: `chart-parameter-${name}` })]));
    this.note = h("p", { class: "muted", id: "history-note" });
    parent.append(
      section("history", "Cost over evaluations", this.note, this.costBox),
      section("estimates", "Estimates over evaluations",
        h("p", { class: "muted" }, truth ? "Dashed: the true value (the simulation's, or as given in the request)." : "No true values are known for these data (they were not simulated here and the request gave none)."),
        h("div", { class: "grid" }, names.map((name) => this.parameterBoxes[name]))));
    this.charts = null;
  }

  async refresh(jobId) {
    const started = performance.now();
    const overview = await api(`/v1/jobs/${jobId}/history?max_points=${MAX_POINTS}`);
    const index = overview.items.map((item) => item.index);
    const cost = positive(overview.items.map((item) => item.cost));
    this.note.textContent = overview.total > overview.items.length
      ? `${overview.total} evaluations; drawn: every ${overview.stride}th with the first, best and last (${overview.items.length} points).`
      : `${overview.total} evaluations.`;
    const data = { cost: [index, cost] };
    for (const name of this.names) {
      const values = overview.items.map((item) => item.parameters[name]);
      data[name] = this.truth && this.truth[name] !== undefined
        ? [index, values, index.map(() => this.truth[name])] : [index, values];
    }
    if (!this.charts) {
      if (!index.length) return;
      this.charts = {
        cost: lineChart(this.costBox, { title: "Input-error cost", xLabel: "evaluation", yLabel: "cost (log)", logY: true,
                                         series: [{ label: "cost" }], data: data.cost }),
      };
      this.names.forEach((name, i) => {
        const series = [{ label: `${name} estimate`, color: PALETTE[i % PALETTE.length] }];
        if (data[name].length === 3) series.push({ label: `${name} true`, color: "#555", dash: [6, 4], width: 1 });
        this.charts[name] = lineChart(this.parameterBoxes[name], { title: name, xLabel: "evaluation", yLabel: name.startsWith("m") ? "kg" : "m",
                                                                   series, data: data[name], height: 200 });
      });
    } else {
      for (const [key, chart] of Object.entries(this.charts)) chart.update(data[key]);
    }
    this.costBox.dataset.total = String(overview.total);
    this.costBox.dataset.drawMs = String(Math.round(performance.now() - started));
  }
}

async function fitSection(parent, jobId) {
  const fit = await api(`/v1/jobs/${jobId}/fit?max_points=${MAX_POINTS}`);
  const boxes = fit.joints.map((joint) => h("div", { id: `chart-fit-${joint.joint}` }));
  const residualBox = h("div", { id: "chart-residual" });
  parent.append(section("fit", "Torque: filtered measured beside the model at the estimate",
    h("p", { class: "muted" }, `Filter M = ${fit.filter.half_length}, Ωg = ${number(fit.filter.band, 4)}; torque ${fit.torque_source}. ` +
      "The input-error cost is the sum over joints of the residual's mean square."),
    h("div", { class: "grid" }, boxes), residualBox));
  fit.joints.forEach((joint, i) => {
    lineChart(boxes[i], {
      title: `Joint ${joint.joint}: rms residual ${number(joint.rms_residual, 3)} of ${number(joint.rms_measured, 3)} N·m`,
      xLabel: "t, s", yLabel: "N·m", height: 200,
      series: [{ label: "measured (filtered)", color: "#333" }, { label: "model", color: PALETTE[i], dash: [5, 3] }],
      data: [fit.t, joint.measured, joint.model] });
  });
  lineChart(residualBox, { title: "Residual, model − measured", xLabel: "t, s", yLabel: "N·m",
                           series: fit.joints.map((joint) => ({ label: `joint ${joint.joint}` })),
                           data: [fit.t, ...fit.joints.map((joint) => joint.residual)] });
}

async function dataSection(parent, datasetId) {
  const data = await api(`/v1/datasets/${datasetId}/data?max_points=${MAX_POINTS}`);
  const joints = data.q.length;
  const angleBox = h("div", { id: "chart-angles" });
  const torqueBox = h("div", { id: "chart-torques" });
  parent.append(section("data", "Measured data", h("p", { class: "muted" },
    `${joints} joints; drawn: ${data.t.length} of the dataset's samples.`), angleBox, data.tau ? torqueBox : null));
  const angleSeries = data.q.map((_, j) => ({ label: `q${j + 1}`, color: PALETTE[j] }));
  const angleData = [data.t, ...data.q];
  if (data.ref) {
    data.ref.forEach((_, j) => angleSeries.push({ label: `ref${j + 1}`, color: PALETTE[j], dash: [4, 4], width: 1 }));
    angleData.push(...data.ref);
  }
  lineChart(angleBox, { title: "Joint angles (dashed: reference)", xLabel: "t, s", yLabel: "rad", series: angleSeries, data: angleData });
  if (data.tau) {
    lineChart(torqueBox, { title: "Joint torques", xLabel: "t, s", yLabel: "N·m",
                           series: data.tau.map((_, j) => ({ label: `tau${j + 1}`, color: PALETTE[j] })), data: [data.t, ...data.tau] });
  }
}

// ---- the view -----------------------------------------------------------------------------

export async function jobView(main, id) {
  let job = await api(`/v1/jobs/${id}`);
  // The paper's pictures (history, true values) are the preset's.
  const onRobot = ["robot_identification", "payload_identification", "excitation"].includes(job.kind);
  const truth = onRobot ? null : await trueValues(job);
  const badge = h("span", { id: "job-state" }, stateBadge(job.state));
  const summary = h("div", {}, summaryList(job));
  const cancel = h("button", { type: "button", id: "cancel", hidden: TERMINAL.includes(job.state) }, "Cancel");
  const body = h("div", { class: "stack" });
  const root = h("article", { id: "job", dataset: { jobId: id } },
    h("h1", {}, `Job ${id} `, badge), h("div", { class: "card" }, summary, cancel), body);
  main.replaceChildren(root);
  document.title = `${id} · manipid`;
  document.body.dataset.jobState = job.state;
  document.body.dataset.ready = "false";

  cancel.addEventListener("click", async () => {
    cancel.disabled = true;
    await api(`/v1/jobs/${id}/cancel`, { method: "POST" }).catch(() => {});
  });

  let history = null;
  if (job.kind === "identification") {
    const names = job.request.free || Object.keys((await api(`/v1/presets/${job.request.preset || "cedro2009"}`)).true_parameters);
    history = new HistoryCharts(body, names, truth);
    await history.refresh(id);
  }
  // For the console and bench/dashboard_bench.mjs: one live refresh on demand.
  window.manipidJob = { id, refreshHistory: () => (history ? history.refresh(id) : Promise.resolve()) };

  const show = (next) => {
    job = next;
    badge.replaceChildren(stateBadge(job.state));
    summary.replaceChildren(summaryList(job));
    cancel.hidden = TERMINAL.includes(job.state);
    document.body.dataset.jobState = job.state;
  };
  while (!TERMINAL.includes(job.state)) {
    await sleep(1000);
    if (!root.isConnected) return;  // the user went elsewhere
    show(await api(`/v1/jobs/${id}`));
    if (history && job.state !== "queued") await history.refresh(id);
  }
  if (history) await history.refresh(id);

  if (job.state === "failed" && job.error) {
    body.prepend(section("error", "Why it failed", h("p", { role: "alert" }, job.error.detail || job.error.title || "unknown error")));
  }
  // A section that cannot be drawn (its dataset deleted since, say) says so in its place;
  // the rest of the page stands.
  const drawOrExplain = async (title, draw) => {
    try {
      await draw();
    } catch (error) {
      body.append(section(`missing-${body.children.length}`, title, h("p", { role: "status" }, error.message || String(error))));
    }
  };
  if (onRobot) {
    if (job.kind === "robot_identification" && job.result) await robotIdentificationSections(body, job, drawOrExplain);
    if (job.kind === "excitation" && job.result) await excitationSections(body, job, drawOrExplain);
    if (job.kind === "payload_identification" && job.state === "succeeded") await payloadSections(body, job, drawOrExplain);
    document.body.dataset.ready = "true";
    return;
  }
  if (job.kind === "identification" && job.result) {
    body.append(resultSection(job.result, truth));
    await drawOrExplain("Torque fit", () => fitSection(body, id));
  }
  if (job.dataset_id) await drawOrExplain("Measured data", () => dataSection(body, job.dataset_id));
  document.body.dataset.ready = "true";  // last: every section is drawn
}

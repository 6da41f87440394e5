// jobs_list.js — the front page: the way to your own arm (URDF robots), a form that starts the
// paper's experiment (simulate + identify) with its defaults filled in from GET
// /v1/presets/cedro2009, and the job list with state and kind filters, newest first, robot jobs
// by their robot's name, refreshed while jobs are active.
import { api, ApiProblem } from "./api.js";
import { h, number, stateBadge, when } from "./dom.js";
import { robotPath } from "./paths.js";

const METHODS = ["input-error", "output-error", "two-stage"];
// "default": the method's own (LM; LN_BOBYQA for output-error), so the field is left out of the request.
const ALGORITHMS = ["default", "LM", "LN_BOBYQA", "LN_NELDERMEAD", "LN_SBPLX", "LD_LBFGS", "LD_SLSQP"];

function field(label, input, hint) {
  const id = input.id;
  return h("div", { class: "field" }, h("label", { for: id }, label), input, hint ? h("small", { id: `${id}-hint` }, hint) : null);
}

function select(id, name, options, value) {
  return h("select", { id, name }, options.map((option) => h("option", { value: option, selected: option === value }, option)));
}

function numberInput(id, name, value, extra = {}) {
  return h("input", { id, name, type: "text", inputmode: "decimal", value: String(value), ...extra });
}

function paperForm(preset, navigate) {
  const names = preset.parameters;
  const status = h("p", { class: "form-status", role: "status", "aria-live": "polite" });
  const form = h("form", { id: "paper-form", class: "card", "aria-labelledby": "paper-form-title", novalidate: true },
    h("h2", { id: "paper-form-title" }, "Run the paper's experiment"),
    h("p", { class: "muted" }, `${preset.description}. Simulate the closed loop, then identify from it — defaults are the paper's.`),
    h("fieldset", {},
      h("legend", {}, "Simulation"),
      h("div", { class: "fields" },
        field("Kinetic energy", select("f-energy", "kinetic_energy", ["complete", "paper"], "complete"),
          "paper: the paper's simplified model (no cross terms)"),
        field("Duration, s", numberInput("f-duration", "duration", preset.simulation.duration)),
        field("Noise on q, rad (σ)", numberInput("f-q-sigma", "q_sigma", 0)),
        field("Noise on τ, fraction of its spread", numberInput("f-tau-relative", "tau_relative_sigma", 0)),
        field("Encoder bits (0: none)", numberInput("f-bits", "quantize_bits", 0, { inputmode: "numeric" })),
        field("Seed", numberInput("f-seed", "seed", 1, { inputmode: "numeric" })))),
    h("fieldset", {},
      h("legend", {}, "Identification"),
      h("div", { class: "fields" },
        field("Method", select("f-method", "method", METHODS, "input-error")),
        field("Algorithm", select("f-algorithm", "algorithm", ALGORITHMS, "default")),
        field("Filter half-length M", numberInput("f-half-length", "half_length", "auto"), "a number, or auto"),
        field("Band Ωg, rad/sample", numberInput("f-band", "band", "auto"), "a number, or auto"),
        field("Torque from", select("f-torque", "torque_source", ["auto", "measured", "reference"], "auto")))),
    h("fieldset", {},
      h("legend", {}, "Free parameters and initial values"),
      h("div", { class: "fields parameters" },
        names.map((name) => h("div", { class: "field parameter" },
          h("input", { id: `f-free-${name}`, type: "checkbox", name: "free", value: name, checked: true }),
          h("label", { for: `f-free-${name}` }, name),
          h("input", { id: `f-initial-${name}`, name: `initial.${name}`, type: "text", inputmode: "decimal",
                       value: String(preset.initial_parameters[name]), "aria-label": `initial ${name}` }))))),
    h("div", { class: "actions" }, h("button", { type: "submit", id: "paper-submit" }, "Run the paper's experiment"), status));

  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const value = (id) => form.querySelector(`#${id}`).value.trim();
    const numeric = (id) => Number(value(id));
    const autoOrNumber = (id) => (value(id).toLowerCase() === "auto" ? "auto" : Number(value(id)));
    const energy = value("f-energy");
    const noise = { q_sigma: numeric("f-q-sigma"), tau_relative_sigma: numeric("f-tau-relative"),
                    quantize_bits: numeric("f-bits"), seed: numeric("f-seed") };
    const simulation = { preset: preset.name, kinetic_energy: energy, duration: numeric("f-duration") };
    if (noise.q_sigma || noise.tau_relative_sigma || noise.quantize_bits) simulation.noise = noise;
    const initial = {};
    for (const name of names) initial[name] = Number(value(`f-initial-${name}`));
    const body = {
      simulation, preset: preset.name, kinetic_energy: energy,
      method: value("f-method"), algorithm: value("f-algorithm") === "default" ? undefined : value("f-algorithm"),
      half_length: autoOrNumber("f-half-length"), band: autoOrNumber("f-band"),
      torque_source: value("f-torque"),
      free: [...form.querySelectorAll("input[name=free]:checked")].map((box) => box.value),
      initial,
    };
    form.querySelectorAll("[aria-invalid]").forEach((element) => element.removeAttribute("aria-invalid"));
    status.textContent = "Submitting…";
    try {
      const job = await api("/v1/identifications", { method: "POST", body });
      navigate(`/jobs/${job.id}`);
    } catch (error) {
      status.textContent = error instanceof ApiProblem ? `${error.field ? error.field + ": " : ""}${error.message}` : String(error);
      status.setAttribute("role", "alert");
      const culprit = error.field && form.querySelector(`[name="${CSS.escape(error.field.replace(/^simulation\.(noise\.)?/, ""))}"]`);
      if (culprit) { culprit.setAttribute("aria-invalid", "true"); culprit.focus(); }
    }
  });
  return form;
}

function jobRow(job, robotNames) {
  const result = job.result || {};
  const paper = job.kind === "identification";  // cost and evaluations: the paper's method's (not a robot_identification's)
  const robotName = robotNames.get(job.robot_id);
  return h("tr", { dataset: { jobId: job.id } },
    h("td", {}, h("a", { href: `/jobs/${job.id}` }, job.id)),
    h("td", {}, job.kind),
    h("td", {}, job.robot_id
      ? h("a", { href: robotPath(job.robot_id), title: job.robot_id, class: "robot-name" }, robotName || job.robot_id)
      : h("span", { class: "muted" }, "preset")),
    h("td", {}, stateBadge(job.state)),
    h("td", {}, when(job.created_at)),
    h("td", { class: "number" }, paper ? number(result.final_cost ?? job.progress.best_cost, 4) : "–"),
    h("td", { class: "number" }, paper ? String(job.progress.evaluations) : "–"));
}

/** A short way to the robots pages, as prominent as the paper's form. */
function robotsCard() {
  return h("section", { id: "robots-card", class: "card", "aria-labelledby": "robots-card-title" },
    h("h2", { id: "robots-card-title" }, "Your own arm"),
    h("p", {}, "Any serial arm described by a URDF: upload it, design an excitation within its limits, identify its base " +
      "parameters and friction from your runs, check them on a run they were not fitted to, and download the identified URDF."),
    h("p", { class: "actions" }, h("a", { href: "/robots", class: "button", id: "robots-card-link" }, "Your own arm: upload a URDF")));
}

/** Robot id → name, from one page of /v1/robots; empty when the list cannot be read (ids are shown then). */
async function robotNames() {
  const page = await api("/v1/robots?page_size=1000").catch(() => ({ items: [] }));
  return new Map((page.items || []).map((robot) => [robot.id, robot.name]));
}

export async function jobsListView(main, navigate) {
  const [preset, names] = await Promise.all([api("/v1/presets/cedro2009"), robotNames()]);
  const stateFilter = select("filter-state", "state", ["any", "queued", "running", "succeeded", "failed", "cancelled"], "any");
  const kindFilter = select("filter-kind", "kind", ["any", "identification", "robot_identification", "payload_identification", "simulation", "excitation"], "any");
  const body = h("tbody");
  const more = h("button", { type: "button", id: "jobs-more", hidden: true }, "Older jobs");
  const table = h("table", { id: "jobs", class: "data" },
    h("caption", {}, "Jobs, newest first"),
    h("thead", {}, h("tr", {}, ["Job", "Kind", "Robot", "State", "Created", "Final cost", "Evaluations"].map((label) => h("th", { scope: "col" }, label)))),
    body);
  main.replaceChildren(
    h("h1", {}, "Jobs"),
    robotsCard(),
    paperForm(preset, navigate),
    h("section", { class: "card", "aria-labelledby": "jobs-title" },
      h("h2", { id: "jobs-title" }, "All jobs"),
      h("div", { class: "filters" },
        h("label", { for: "filter-state" }, "State"), stateFilter,
        h("label", { for: "filter-kind" }, "Kind"), kindFilter),
      h("div", { class: "scroll" }, table), more));

  let token = null;
  const missing = new Set();  // robot ids /v1/robots does not know (deleted robots)
  const query = () => {
    const parts = [];
    if (stateFilter.value !== "any") parts.push(`state=${stateFilter.value}`);
    if (kindFilter.value !== "any") parts.push(`kind=${kindFilter.value}`);
    return parts;
  };
  async function load(append) {
    const parts = query();
    if (append && token) parts.push(`page_token=${encodeURIComponent(token)}`);
    const page = await api(`/v1/jobs${parts.length ? "?" + parts.join("&") : ""}`);
    // A robot uploaded since the page was drawn: look the names up again (one call), once per unknown id.
    const unknown = page.items.filter((job) => job.robot_id && !names.has(job.robot_id) && !missing.has(job.robot_id));
    if (unknown.length) {
      for (const [id, name] of await robotNames()) names.set(id, name);
      for (const job of unknown) if (!names.has(job.robot_id)) missing.add(job.robot_id);
    }
    const rows = page.items.map((job) => jobRow(job, names));
    if (append) body.append(...rows);
    else body.replaceChildren(...rows);
    if (!body.children.length) body.append(h("tr", {}, h("td", { colspan: 7, class: "muted" }, "No jobs yet.")));
    token = page.next_page_token || null;
    more.hidden = !token;
    return page.items;
  }
  stateFilter.addEventListener("change", () => load(false));
  kindFilter.addEventListener("change", () => load(false));
  more.addEventListener("click", () => load(true));
  await load(false);
  document.body.dataset.ready = "true";

  // Refresh the first page while anything on it is still queued or running.
  const timer = setInterval(async () => {
    if (!main.contains(table)) { clearInterval(timer); return; }
    const active = [...body.querySelectorAll(".badge")].some((badge) => ["queued", "running"].includes(badge.dataset.state));
    if (active && !token) await load(false).catch(() => {});
  }, 2000);
}

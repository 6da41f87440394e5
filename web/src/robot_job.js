// robot_job.js — the sections of a job on a URDF robot (/jobs/{id} when the job has robot_id).
// An identification: what it found at a glance, the base parameters (filterable, sortable) and
// their correlation map, friction per joint, physical consistency and identifiability in words,
// the filtered measured torque beside the model's per joint (small multiples), the friction
// curves (what the rigid-body model leaves against q̇, with the fitted law), the validation run
// predicted by the estimate beside the URDF's own values, and the run's raw angles and torques.
// An excitation: the design's figures, the share of each limit it uses per joint, and each joint's
// angle, velocity, acceleration and torque over the run against its limits.
import { api, downloadLink } from "./api.js";
import { lineChart, PALETTE } from "./charts.js";
import { facts, h, number, percent, plural, section } from "./dom.js";
import { jobPath, robotPath } from "./paths.js";

// Points per joint chart: a small multiple is 400–700 px wide, so 1000 points draw every pixel.
export const JOINT_POINTS = 1000;
// Points of the measured data's charts: they are as wide as the page.
export const DATA_POINTS = 2000;
// The most correlated pairs listed by name under the map, and what counts as strongly correlated.
const PAIRS = 10, STRONG = 0.9;
// Relative standard error thresholds for the base-parameter table.
const WELL = 0.1, DETERMINED = 1;

const isPrismatic = (joint) => joint?.type === "prismatic";
export const torqueUnit = (joint) => (isPrismatic(joint) ? "N" : "N·m");

// ---- at a glance ----------------------------------------------------------------------------

function consistencyInWords(result) {
  const check = result.consistency;
  if (!check) return "not assessed";
  if (check.consistent) return "consistent: every link is a possible rigid body";
  const bad = (check.links || []).filter((link) => !link.consistent);
  return bad.length
    ? `not consistent: ${bad.length} of ${plural((check.links || []).length, "link")} (${bad.map((link) => link.link).join(", ")})`
    : "not consistent";
}

/** "judged under a zero-phase Butterworth low-pass at 5 Hz, 0.3 s trimmed at each end". */
export function judgeInWords(judge) {
  if (!judge) return "judged under the identification's filters";
  return `judged under a zero-phase 4th-order Butterworth low-pass at ${number(judge.cutoff_hz, 3)} Hz, ` +
         `${number(judge.trim_seconds, 3)} s trimmed at each end`;
}

function glance(job, result) {
  const joints = result.robot?.joints?.length ?? result.friction?.length ?? 0;
  const validation = result.validation;
  const held = job.request?.validation_dataset_ids?.length || 1;
  const unexcited = result.unexcited || [];
  return section("glance", "At a glance",
    facts([
      ["Robot", [h("a", { href: robotPath(job.robot_id), id: "robot-link" }, result.robot?.name || job.robot_id),
                 ` — ${plural(joints, "joint")}, ${result.robot?.base_link ?? "?"} → ${result.robot?.tip_link ?? "?"}`]],
      ["Base parameters", [`${result.base_parameters.length} estimated`,
                           unexcited.length ? `, ${unexcited.length} barely seen by the data (kept near the URDF's values)` : ", every one seen by the data"]],
      ["Condition number", h("span", { id: "condition-number" }, number(result.condition_number, 4))],
      ["Fit error", [h("span", { id: "fit-overall" }, percent(result.fit?.overall_relative_error)),
                     ` of the measured torque (‖τ̂ − τ‖ / ‖τ‖ over the fitted joints), ${judgeInWords(result.judge)}`]],
      ["Validation error", validation
        ? [h("span", { id: "validation-overall" }, percent(validation.overall_relative_error)),
           ` on ${held > 1 ? `the ${held} validation runs` : "the validation run"}; the URDF's own values: ${percent(validation.prior?.overall_relative_error)}`]
        : "no validation run"],
      ["Physical consistency", h("span", { id: "consistency-glance" }, consistencyInWords(result))],
      ["Warnings", result.warnings?.length ? h("a", { href: "#identifiability" }, plural(result.warnings.length, "warning")) : "none"],
    ]),
    urdfActions(job, result));
}

/**
 * The identified URDF: a download when every link is a real body; else why there is none and the
 * way to one — the same request again with physical consistency (a URDF holds only real bodies).
 */
function urdfActions(job, result) {
  if (result.consistency?.consistent !== false) {
    return h("p", { class: "actions" },
      downloadLink(`/v1/jobs/${job.id}/urdf`, "Download the identified URDF", { id: "urdf-download", class: "button" }),
      h("span", { class: "muted" }, "The robot's document with the estimate in its <inertial> and <dynamics> elements, " +
        "opened by a comment saying where it came from."));
  }
  const bad = (result.consistency.links || []).filter((link) => !link.consistent).map((link) => link.link);
  return h("div", { id: "urdf-unavailable", class: "actions" },
    h("p", {}, h("strong", {}, "No identified URDF: "),
      `a URDF holds only real rigid bodies, and ${bad.length ? bad.join(", ") : "some links"} of this estimate ` +
      `${bad.length === 1 ? "is" : "are"} not (see `, h("a", { href: "#consistency" }, "Physical consistency"), "). " +
      "The same identification with physical consistency keeps every link a real body, fitting the data as closely as that allows."),
    h("p", {}, againWithPhysical(job, "identify-physical", "Identify again, physically consistent")));
}

/**
 * A button that submits the job's request again with physical: true and opens the new job's page, and the
 * status beside it (what was refused, if it was).
 */
export function againWithPhysical(job, id, label) {
  const status = h("span", { class: "form-status", role: "status", "aria-live": "polite" });
  const again = h("button", { type: "button", id }, label);
  again.addEventListener("click", async () => {
    again.disabled = true;
    status.textContent = "Submitting…";
    try {
      const next = await api("/v1/identifications", { method: "POST", body: { ...job.request, physical: true } });
      window.location.assign(jobPath(next.id));
    } catch (error) {
      status.textContent = error.message || "The request was refused.";
      again.disabled = false;
    }
  });
  return [again, " ", status];
}

// ---- the links as the URDF holds them ---------------------------------------------------------

const DETERMINED_TEXT = (determined) =>
  determined?.inertia_about_com ? "all"
    : determined?.centre_of_mass ? "mass, centre of mass"
      : determined?.mass ? "mass" : "only in combinations";

function linkSection(result) {
  const links = result.links || [];
  if (!links.length) return section("links", "Links", h("p", {}, "This result carries no link table."));
  const cell = (value, digits = 4) => h("td", { class: "number" }, number(value, digits));
  return section("links", "Links as the URDF holds them",
    h("p", { class: "muted" }, "Each link's mass, centre of mass (in the link's frame) and inertia about it (in the link's axes), " +
      "as the identified URDF writes them. \u201cDetermined by the data\u201d: a value the runs fix alone; the rest move only " +
      "in sums with other links' parameters and, where the data are silent, keep the URDF's values."),
    h("div", { class: "scroll" }, h("table", { id: "links-table", class: "data" },
      h("thead", {}, h("tr", {}, ["Link", "Mass, kg", "x, m", "y, m", "z, m", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz",
                                  "Determined by the data"].map((label) => h("th", { scope: "col" }, label)))),
      h("tbody", {}, links.map((link) => {
        const c = link.centre_of_mass || [], I = link.inertia_about_com || {};
        return h("tr", { dataset: { link: link.link, mass: String(link.mass), determined: DETERMINED_TEXT(link.determined) } },
          h("th", { scope: "row" }, link.link, link.consistent ? null : [" ", h("span", { class: "badge state-failed" }, "not a real body")]),
          cell(link.mass), cell(c[0], 3), cell(c[1], 3), cell(c[2], 3),
          cell(I.ixx, 3), cell(I.ixy, 3), cell(I.ixz, 3), cell(I.iyy, 3), cell(I.iyz, 3), cell(I.izz, 3),
          h("td", {}, DETERMINED_TEXT(link.determined)));
      })))),
    h("p", { class: "muted" }, "Inertia in kg·m² (URDF tensor entries)."));
}

// ---- base parameters ------------------------------------------------------------------------

/** "a + b - c" → ["a", "+ b", "- c"]: the terms of a base parameter's name. */
function terms(name) {
  return name.split(/ (?=[+-] )/);
}

/** A base parameter's name, wrapping between terms; past four terms, the first three and a toggle. */
function expression(name) {
  const parts = terms(name);
  const spans = (list) => list.map((term, i) => [i ? " " : "", h("span", { class: "term" }, term)]);
  if (parts.length <= 4) return h("span", { class: "expr" }, spans(parts));
  const short = h("span", { class: "expr" }, spans(parts.slice(0, 3)), " …");
  const full = h("span", { class: "expr", hidden: true }, spans(parts));
  const more = `+${parts.length - 3} terms`;
  const toggle = h("button", { type: "button", class: "inline", "aria-expanded": "false",
                               "aria-label": `show all ${parts.length} terms` }, more);
  toggle.addEventListener("click", () => {
    const open = toggle.getAttribute("aria-expanded") !== "true";
    short.hidden = open;
    full.hidden = !open;
    toggle.setAttribute("aria-expanded", String(open));
    toggle.setAttribute("aria-label", open ? "show fewer terms" : `show all ${parts.length} terms`);
    toggle.textContent = open ? "fewer" : more;
  });
  return [short, full, " ", toggle];
}

function quality(parameter, unexcited) {
  if (unexcited) return "unexcited";
  const relative = parameter.relative_std_error;
  if (relative === null || relative === undefined) return "unknown";
  return relative <= WELL ? "well" : relative <= DETERMINED ? "weak" : "poor";
}

const QUALITY_TEXT = { well: "", weak: "weakly determined", poor: "not determined", unexcited: "", unknown: "" };

function baseParameterRow(parameter, index, unexcited) {
  const kind = quality(parameter, unexcited);
  const value = (x) => (x === null || x === undefined ? "" : String(x));
  return h("tr", { class: `quality-${kind}`, dataset: { index: String(index + 1), name: parameter.name, quality: kind,
                                                         estimate: value(parameter.estimate), stdError: value(parameter.std_error),
                                                         relative: value(parameter.relative_std_error) } },
    h("td", { class: "number" }, String(index + 1)),
    h("th", { scope: "row", class: "name", title: parameter.name }, expression(parameter.name),
      unexcited ? [" ", h("span", { class: "badge unexcited" },
        `barely seen: ${percent(parameter.data_share ?? 0, 2)} data, the rest the URDF's value`)] : null),
    h("td", { class: "number", dataset: { estimate: value(parameter.estimate) } }, number(parameter.estimate, 6)),
    h("td", { class: "number", dataset: { stdError: value(parameter.std_error) } }, number(parameter.std_error, 3)),
    h("td", { class: `number relative ${kind}`, dataset: { relative: value(parameter.relative_std_error) } },
      percent(parameter.relative_std_error, 3),
      QUALITY_TEXT[kind] ? h("span", { class: "visually-hidden" }, ` (${QUALITY_TEXT[kind]})`) : null));
}

const COLUMNS = [
  { key: "index", label: "#", numeric: true },
  { key: "name", label: "Base parameter", numeric: false },
  { key: "estimate", label: "Estimate", numeric: true },
  { key: "stdError", label: "Std error σ", numeric: true },
  { key: "relative", label: "Relative σ", numeric: true },
];

function baseParameterSection(result) {
  const unexcited = new Set(result.unexcited || []);
  const rows = result.base_parameters.map((parameter, i) => baseParameterRow(parameter, i, unexcited.has(parameter.name)));
  const tbody = h("tbody", {}, rows);
  const filter = h("input", { type: "search", id: "base-filter", autocomplete: "off", spellcheck: "false",
                              placeholder: "e.g. Izz or m7", "aria-controls": "base-table" });
  const show = h("select", { id: "base-quality", "aria-controls": "base-table" },
    [["all", "all"], ["uncertain", "σ over 10 % of the estimate"], ["well", "σ within 10 %"], ["unexcited", "barely seen by the data"]]
      .map(([value, label]) => h("option", { value }, label)));
  const status = h("p", { id: "base-count", class: "muted", role: "status", "aria-live": "polite" });

  const apply = () => {
    const text = filter.value.trim().toLowerCase();
    let visible = 0;
    for (const row of rows) {
      const kind = row.dataset.quality;
      const wanted = show.value === "all" || show.value === kind ||
                     (show.value === "uncertain" && (kind === "weak" || kind === "poor"));
      row.hidden = !(wanted && (!text || row.dataset.name.toLowerCase().includes(text)));
      if (!row.hidden) visible += 1;
    }
    status.textContent = visible === rows.length ? `${rows.length} base parameters.` : `Showing ${visible} of ${rows.length} base parameters.`;
  };
  filter.addEventListener("input", apply);
  show.addEventListener("change", apply);

  // Sorting: a button in each header; absent values (null) last whichever the direction.
  const headers = COLUMNS.map((column) => {
    const button = h("button", { type: "button", class: "sort", dataset: { key: column.key } }, column.label);
    const th = h("th", { scope: "col", class: column.numeric ? "number" : null }, button);
    button.addEventListener("click", () => {
      const ascending = th.getAttribute("aria-sort") !== "ascending";
      for (const other of headers) other.removeAttribute("aria-sort");
      th.setAttribute("aria-sort", ascending ? "ascending" : "descending");
      const key = (row) => {
        const raw = row.dataset[column.key];
        return column.numeric ? (raw === "" ? null : column.key === "estimate" ? Math.abs(Number(raw)) : Number(raw)) : raw;
      };
      const sorted = [...rows].sort((a, b) => {
        const x = key(a), y = key(b);
        if (x === null || y === null) return x === null ? (y === null ? 0 : 1) : -1;
        const order = column.numeric ? x - y : x.localeCompare(y);
        return ascending ? order : -order;
      });
      tbody.replaceChildren(...sorted);
    });
    return th;
  });
  headers[0].setAttribute("aria-sort", "ascending");
  apply();

  return section("base-parameters", "Base parameters",
    h("p", { class: "muted" },
      "The combinations of standard parameters the torques determine; σ from the least-squares covariance. Relative σ is " +
      "|σ / estimate|: amber over 10 %, red over 100 % — the data do not determine the value (often one whose true value is near " +
      "zero). Estimates sort by magnitude."),
    h("div", { class: "filters" },
      h("label", { for: "base-filter" }, "Name contains"), filter,
      h("label", { for: "base-quality" }, "Show"), show),
    status,
    h("div", { class: "scroll" }, h("table", { id: "base-table", class: "data base" },
      h("caption", {}, "Base parameters (SI units: kg, kg·m, kg·m², and friction's units)"),
      h("thead", {}, h("tr", {}, headers)),
      tbody)));
}

// ---- correlation of the base parameters ---------------------------------------------------------

function heatColor(value) {
  if (value === null || value === undefined || Number.isNaN(value)) return "#f2f2f2";
  const strength = Math.min(1, Math.abs(value));
  return `hsl(${value >= 0 ? 0 : 220} 75% ${100 - 45 * strength}%)`;  // red positive, blue negative
}

/**
 * The base parameters' correlation (base × base, result.correlation) as a map of small cells numbered as the
 * table's rows, each cell's pair and value in its title (on hover); the strongest pairs by name below it.
 */
function correlationSection(result) {
  const matrix = result.correlation || [];
  const names = result.base_parameters.map((parameter) => parameter.name);
  if (!matrix.length || matrix.length !== names.length) {
    return section("correlation", "Correlation of the base parameters", h("p", {}, "This result carries no correlation matrix."));
  }
  const text = (value) => (typeof value === "number" ? value.toFixed(2) : "–");
  const label = (i) => `#${i + 1} ${names[i]}`;
  const pairs = [];
  matrix.forEach((row, i) => row.forEach((value, j) => { if (j > i && typeof value === "number") pairs.push({ i, j, value }); }));
  pairs.sort((a, b) => Math.abs(b.value) - Math.abs(a.value));
  const strong = pairs.filter((pair) => Math.abs(pair.value) >= STRONG).length;
  const tick = (i) => ((i + 1) % 5 === 0 || i === 0 ? String(i + 1) : "");
  const map = h("table", { id: "correlation-map", class: "heat map", dataset: { size: String(names.length) } },
    h("caption", { class: "visually-hidden" }, `Correlation of the ${names.length} base parameters, numbered as the table above`),
    h("thead", {}, h("tr", {}, h("td", {}),
      names.map((name, j) => h("th", { scope: "col", title: label(j) }, h("span", { class: "tick" }, tick(j)))))),
    h("tbody", {}, matrix.map((row, i) => h("tr", {},
      h("th", { scope: "row", title: label(i) }, tick(i)),
      row.map((value, j) => h("td", { style: `background:${heatColor(value)}`, title: `corr(${label(i)}, ${label(j)}) = ${text(value)}` }))))));
  const legend = h("p", { class: "key", "aria-hidden": "true" },
    [-1, -0.5, 0, 0.5, 1].map((value) => h("span", {}, h("span", { class: "swatch-box", style: `background:${heatColor(value)}` }), ` ${value}`)));
  return section("correlation", "Correlation of the base parameters",
    h("p", { class: "muted" }, "Red +1, blue −1: how the estimates' errors move together (from the least-squares covariance). " +
      "A strongly correlated pair is told apart only by what little of the data moves one without the other. " +
      `${names.length} × ${names.length}, numbered as the table above; point at a cell for its pair and value.`),
    legend,
    h("div", { class: "scroll" }, map),
    h("h3", {}, "The most correlated pairs"),
    h("p", { id: "correlation-strong-count", dataset: { count: String(strong) } },
      strong ? `${plural(strong, "pair")} correlated ±${STRONG} or more; the ${Math.min(PAIRS, pairs.length)} strongest:`
        : `No two base parameters are correlated ±${STRONG} or more; the ${Math.min(PAIRS, pairs.length)} strongest pairs:`),
    h("ul", { id: "correlation-strong", class: "strong-pairs" }, pairs.slice(0, PAIRS).map(({ i, j, value }) =>
      h("li", { dataset: { i: String(i + 1), j: String(j + 1), value: String(value) } },
        h("strong", {}, text(value)), ": ", h("code", {}, label(i)), " and ", h("code", {}, label(j))))));
}

// ---- friction -------------------------------------------------------------------------------

const FRICTION = {
  fv: { label: "Viscous fv", unit: "N·m·s/rad", prismaticUnit: "N·s/m" },
  fc: { label: "Coulomb fc", unit: "N·m", prismaticUnit: "N" },
  fo: { label: "Offset fo", unit: "N·m", prismaticUnit: "N" },
  Ia: { label: "Armature Ia", unit: "kg·m²", prismaticUnit: "kg" },
};

function frictionSection(result) {
  const entries = result.friction || [];
  const keys = Object.keys(FRICTION).filter((key) => entries.some((entry) => key in entry));
  if (!entries.length || !keys.length) {
    return section("friction", "Friction", h("p", {}, "No friction or armature terms were estimated (the request's friction was [])."));
  }
  const joints = result.robot?.joints || [];
  const base = new Map(result.base_parameters.map((parameter) => [parameter.name, parameter]));
  const prismatic = joints.some(isPrismatic);
  const head1 = h("tr", {}, h("th", { scope: "col", rowspan: 2 }, "Joint"),
    keys.map((key) => h("th", { scope: "colgroup", colspan: 3, class: "group" }, `${FRICTION[key].label}, ${FRICTION[key].unit}`)));
  const head2 = h("tr", {}, keys.map(() => [h("th", { scope: "col", class: "number" }, "estimate"),
                                            h("th", { scope: "col", class: "number" }, "σ"),
                                            h("th", { scope: "col", class: "number" }, "URDF")]));
  const rows = entries.map((entry, j) => h("tr", { dataset: { joint: entry.joint } },
    h("th", { scope: "row" }, entry.joint),
    keys.map((key) => {
      const name = `${key}${j + 1}`;
      const value = entry[key];
      const negative = key !== "fo" && typeof value === "number" && value < 0;
      const alone = base.get(name);
      return [
        h("td", { class: `number${negative ? " unphysical" : ""}`, dataset: { key, value: String(value) } }, number(value, 4),
          negative ? h("span", { class: "flag", title: "negative: not a physical friction" }, " (negative)") : null),
        h("td", { class: "number" }, alone ? number(alone.std_error, 2) : h("span", { class: "muted", title: `${name} is not a base parameter on its own` }, "in a sum")),
        h("td", { class: "number muted" }, number(result.prior?.[name], 4)),
      ];
    })));
  return section("friction", "Friction per joint",
    h("p", { class: "muted" }, "τ += fv·q̇ + fc·sign(q̇)" + (keys.includes("fo") ? " + fo" : "") + (keys.includes("Ia") ? " + Ia·q̈" : "") +
      ". URDF: the robot's <dynamics> damping and friction." + (prismatic ? " Prismatic joints: N·s/m, N and kg." : "")),
    h("div", { class: "scroll" }, h("table", { id: "friction-table", class: "data" }, h("thead", {}, head1, head2), h("tbody", {}, rows))));
}

// ---- consistency and identifiability --------------------------------------------------------

function scalarFacts(object, skip) {
  return Object.entries(object)
    .filter(([key, value]) => !skip.includes(key) && ["number", "string", "boolean"].includes(typeof value))
    .map(([key, value]) => [key.replaceAll("_", " "), typeof value === "number" ? number(value, 4) : String(value)]);
}

function consistencySection(result) {
  const check = result.consistency;
  const parts = [];
  if (!check) {
    parts.push(h("p", { id: "consistency-verdict", dataset: { consistent: "unknown" } },
      h("strong", {}, "Not assessed: "), "this result carries no physical-consistency check of the estimate."));
  } else {
    const links = check.links || [];
    const bad = links.filter((link) => !link.consistent);
    parts.push(h("p", { id: "consistency-verdict", dataset: { consistent: String(Boolean(check.consistent)) } },
      check.consistent
        ? [h("strong", {}, "Physically consistent: "), "every link's estimate is a possible rigid body."]
        : [h("strong", {}, "Not physically consistent: "),
           bad.length ? `${bad.length} of ${plural(links.length, "link")} cannot be rigid bodies with these values.` : "see the findings."]));
    if (check.findings?.length) parts.push(h("ul", { id: "consistency-findings" }, check.findings.map((text) => h("li", {}, text))));
    if (links.length) {
      parts.push(h("div", { class: "scroll" }, h("table", { id: "consistency-links", class: "data" },
        h("thead", {}, h("tr", {}, ["Link", "Verdict", "Findings"].map((label) => h("th", { scope: "col" }, label)))),
        h("tbody", {}, links.map((link) => h("tr", { dataset: { link: link.link, consistent: String(Boolean(link.consistent)) } },
          h("th", { scope: "row" }, link.link),
          h("td", { class: link.consistent ? "ok" : "bad" }, link.consistent ? "✓ consistent" : "✗ not consistent"),
          h("td", { class: "findings" }, link.findings?.length ? h("ul", {}, link.findings.map((text) => h("li", {}, text))) : "–")))))));
    }
  }
  if (result.physical) {
    const physical = result.physical;
    parts.push(h("h3", {}, "Constrained to physical values"),
      h("p", { id: "physical-summary" },
        typeof physical.cost_increase === "number"
          ? `Asked for a physically consistent estimate: its cost is ${percent(physical.cost_increase)} above the unconstrained least squares.`
          : "Asked for a physically consistent estimate.",
        physical.message ? ` ${physical.message}` : ""),
      facts(scalarFacts(physical, ["cost_increase", "message"])));
  }
  return section("consistency", "Physical consistency", parts);
}

/** The names among `names` whose point differs from the prior (the physical fit moved them), with both values. */
function moved(result, names) {
  const point = result.point || {}, prior = result.prior || {};
  return names.filter((name) => typeof point[name] === "number" && typeof prior[name] === "number" &&
                                Math.abs(point[name] - prior[name]) > 1e-9 * Math.max(1, Math.abs(prior[name])))
              .map((name) => ({ name, prior: prior[name], point: point[name] }));
}

function identifiabilitySection(result) {
  const unidentifiable = result.unidentifiable || [];
  const unexcited = result.unexcited || [];
  const filters = result.filters || {};
  const selection = result.selection || {};
  const filter = (f) => (f ? `M = ${f.half_length}, Ωg = ${number(f.band, 3)} rad/sample (${number(f.cutoff_hz, 3)} Hz)` : "–");
  const candidates = selection.candidates || [];
  const chosen = (c) => c.comparison_cutoff_hz === filters.comparison?.cutoff_hz && c.ridge === selection.ridge &&
                        c.friction === (result.parameters?.friction?.join(",") || "none");
  return section("identifiability", "Identifiability and data",
    facts([
      ["Condition number", `${number(result.condition_number, 4)} (the column-scaled base regressor's σmax/σmin: how well the data excite it)`],
      ["Not excited", unexcited.length ? h("ul", { id: "unexcited", class: "names" }, unexcited.map((name) => h("li", {}, h("code", {}, name)))) : "none"],
      ["Never in the torque", unidentifiable.length
        ? h("details", { id: "unidentifiable" },
            h("summary", {}, `${plural(unidentifiable.length, "standard parameter")}: kept at the URDF's values` +
              (moved(result, unidentifiable).length
                ? `, but ${moved(result, unidentifiable).length} moved by the physical fit to make their links real bodies nearest the URDF's values`
                : "")),
            h("ul", { class: "names" }, unidentifiable.map((name) => {
              const shift = moved(result, [name])[0];
              return h("li", { dataset: shift ? { moved: "true" } : {} }, h("code", {}, name),
                shift ? ` ${number(shift.prior, 4)} → ${number(shift.point, 4)}` : null);
            })))
        : "none"],
      ["Differentiation filter", filter(filters.differentiation)],
      ["Comparison low-pass", filters.comparison
        ? `zero-phase Butterworth at ${number(filters.comparison.cutoff_hz, 3)} Hz, on τ and the regressor alike` : "–"],
      ["Ridge toward the URDF", selection.ridge !== undefined ? number(selection.ridge, 3) : null],
      ["Chosen by", selection.by_held_out
        ? `held-out prediction: ${percent(selection.held_out_error)} error on the blocks each fit did not see`
        : "the request (nothing was chosen)"],
      ["Judged under", judgeInWords(result.judge)],
      ["Fitted joints", result.torque_joints ? result.torque_joints.join(", ") : null],
      ["Rows", result.rows !== undefined ? `${result.rows} regressor rows from ${plural(result.runs ?? 1, "run")}` : null],
      ["Method", `${result.method}, ${number(result.wall_seconds, 3)} s`],
    ]),
    candidates.length
      ? h("details", { id: "candidates" },
          h("summary", {}, `${plural(candidates.length, "candidate")} tried by held-out prediction`),
          h("div", { class: "scroll" }, h("table", { class: "data" },
            h("thead", {}, h("tr", {}, ["Comparison low-pass", "Friction", "Ridge", "Held-out error"].map((label) => h("th", { scope: "col" }, label)))),
            h("tbody", {}, candidates.map((c) => h("tr", { class: chosen(c) ? "chosen" : "" },
              h("td", { class: "number" }, `${number(c.comparison_cutoff_hz, 3)} Hz`),
              h("td", {}, c.friction),
              h("td", { class: "number" }, number(c.ridge, 2)),
              h("td", { class: "number" }, percent(c.held_out_error), chosen(c) ? " ← chosen" : "")))))))
      : null,
    h("h3", {}, "Warnings"),
    result.warnings?.length
      ? h("ul", { class: "warnings", id: "warnings" }, result.warnings.map((warning) => h("li", {}, warning)))
      : h("p", { id: "warnings" }, "None."));
}

// ---- per-joint charts -------------------------------------------------------------------------

/**
 * Small multiples: one chart per joint over a shared time axis (the cursor follows across them),
 * and a switch between the torques and the residual. `extra` ({field, label}): a third torque per
 * joint, fit.joints[i][field], drawn dotted beside the two (a payload's arm alone). Returns the element.
 */
export function jointTorqueCharts(id, fit, joints, { measuredLabel, modelLabel, extra = null }) {
  const boxes = fit.joints.map((joint) => h("div", { id: `chart-${id}-${joint.joint}`, dataset: { jointName: joint.name } }));
  const choice = (value, label, checked) => h("label", {},
    h("input", { type: "radio", name: `${id}-plot`, value, checked }), ` ${label}`);
  const toggle = h("fieldset", { class: "toggle" }, h("legend", {}, "Plot"),
    choice("torque", `${measuredLabel} and ${modelLabel}`, true), choice("residual", `residual (${modelLabel} − measured)`, false));
  // One key for every chart (a legend under each would repeat it n times).
  const key = h("p", { class: "key", "aria-hidden": "true" },
    h("span", {}, h("span", { class: "swatch measured" }), ` ${measuredLabel}`),
    h("span", {}, h("span", { class: "swatch model" }), ` ${modelLabel} (dashed, a colour per joint)`),
    extra ? h("span", {}, h("span", { class: "swatch extra" }), ` ${extra.label} (dotted)`) : null,
    h("span", {}, h("span", { class: "swatch residual" }), " residual"));
  const element = h("div", { class: "joint-charts" }, toggle, key, h("div", { class: "grid joints" }, boxes));
  const charts = [];
  // Drawn once the boxes are on the page (they take their width from it); data-draw-ms says how
  // long the n charts took (for people reading the DOM and the end-to-end test's log).
  element.draw = () => {
    const started = performance.now();
    fit.joints.forEach((joint, i) => drawJoint(joint, i));
    element.dataset.drawMs = String(Math.round(performance.now() - started));
  };
  const drawJoint = (joint, i) => {
    const meta = joints[joint.joint - 1];  // the fitted joints may be fewer than the robot's
    const series = [{ label: measuredLabel, color: "#333" }, { label: modelLabel, color: PALETTE[i % PALETTE.length], dash: [5, 3] },
                    { label: "residual", color: "#b42318", show: false }];
    const data = [fit.t, joint.measured, joint.model, joint.residual];
    if (extra) {
      series.push({ label: extra.label, color: "#8a8a8a", dash: [2, 3] });
      data.push(joint[extra.field]);
    }
    charts.push(lineChart(boxes[i], {
      title: `${joint.name}: error ${percent(joint.relative_error)}`,
      xLabel: "t, s", yLabel: `τ, ${torqueUnit(meta)}`, height: 200, sync: id, legend: false, series, data }));
  };
  toggle.addEventListener("change", () => {
    const torque = toggle.querySelector("input:checked").value === "torque";
    for (const chart of charts) {
      chart.showSeries(0, torque);
      chart.showSeries(1, torque);
      chart.showSeries(2, !torque);
      if (extra) chart.showSeries(3, torque);
    }
  });
  return element;
}

async function fitSection(body, job, result) {
  const fit = await api(`/v1/jobs/${job.id}/fit?max_points=${JOINT_POINTS}`);
  const charts = jointTorqueCharts("robot-fit", fit, result.robot?.joints || [], { measuredLabel: "measured (filtered)", modelLabel: "model" });
  body.append(section("robot-fit", "Torque fit per joint",
    h("p", { class: "muted", dataset: { maxPoints: String(JOINT_POINTS) } },
      `The filtered measured torque beside the model's at the estimate: ${fit.samples} filtered samples, drawn ${fit.t.length}. ` +
      `Overall error ‖τ̂ − τ‖ / ‖τ‖ ${percent(fit.overall_relative_error)}; each chart's title gives its joint's.`),
    charts));
  charts.draw();
  if (fit.friction) {
    const curves = frictionCurves(fit.friction, result.robot?.joints || [], fit.judge);
    body.append(curves);
    curves.draw();
  }
}

/** fv·q̇ + fc·sign(q̇) + fo with the terms the law has (sign(0) = 0, as the model's). */
const frictionLaw = (law, qd) => (law.fv ?? 0) * qd + (law.fc ?? 0) * Math.sign(qd) + (law.fo ?? 0);

/** "fv 0.251, fc 0.601" (the units are the friction table's). */
function lawInWords(law) {
  return ["fv", "fc", "fo"].filter((key) => law[key] !== undefined).map((key) => `${key} ${number(law[key], 3)}`).join(", ");
}

/**
 * Friction curves (the /fit answer's "friction"): per joint, what the rigid-body model leaves of the measured
 * torque against q̇, as points, with the fitted law over them. Returns the section; its draw() draws the charts.
 */
function frictionCurves(friction, joints, judge) {
  const boxes = friction.joints.map((joint) => h("div", { id: `chart-friction-${joint.joint}`,
    dataset: { jointName: joint.name, ...Object.fromEntries(Object.entries(joint.law).map(([key, value]) => [key, String(value)])) } }));
  const terms = ["fv·q̇", "fc·sign(q̇)", "fo"].filter((_, i) => friction.terms.includes(["viscous", "coulomb", "offset"][i]));
  const element = section("friction-curves", "Friction curves per joint",
    h("p", { class: "muted" },
      `Each dot: the filtered measured torque less the model's rigid-body part at the estimate (its friction set to 0) — ` +
      `what friction must explain — against the joint's velocity q̇, both through the fit's ${number(judge?.cutoff_hz, 3)} Hz ` +
      `low-pass. The line: the fitted law ${terms.join(" + ")}. Near q̇ = 0 the low-pass smooths the Coulomb step, ` +
      "so there the dots cross between the law's two branches. Units as in the friction table."),
    h("p", { class: "key", "aria-hidden": "true" },
      h("span", {}, h("span", { class: "dot" }), " measured − rigid body"),
      h("span", {}, h("span", { class: "swatch model solid" }), " fitted law (a colour per joint)")),
    h("div", { class: "grid joints" }, boxes));
  element.draw = () => friction.joints.forEach((joint, i) => {
    const meta = joints[joint.joint - 1];
    const order = joint.qd.map((_, k) => k).filter((k) => typeof joint.qd[k] === "number" && typeof joint.torque[k] === "number")
      .sort((a, b) => joint.qd[a] - joint.qd[b]);
    const qd = order.map((k) => joint.qd[k]);
    lineChart(boxes[i], {
      title: `${joint.name}: ${lawInWords(joint.law)}`,
      xLabel: isPrismatic(meta) ? "q̇, m/s" : "q̇, rad/s", yLabel: `τ, ${torqueUnit(meta)}`, height: 220, legend: false,
      series: [{ label: "measured − rigid body", color: "#7a7a7a", points: true },
               { label: "fitted law", color: PALETTE[i % PALETTE.length], width: 2 }],
      data: [qd, order.map((k) => joint.torque[k]), qd.map((v) => frictionLaw(joint.law, v))] });
  });
  return element;
}

/** The identification's run as measured (its first run when there were several): joint angles and torques. */
export async function measuredDataSection(body, job, result) {
  const data = await api(`/v1/datasets/${job.dataset_id}/data?max_points=${DATA_POINTS}`);
  const joints = result.robot?.joints || [];
  const name = (j) => joints[j]?.name || `joint ${j + 1}`;
  const runs = job.request?.dataset_ids?.length || 1;
  const angleBox = h("div", { id: "chart-robot-angles" });
  const torqueBox = h("div", { id: "chart-robot-torques" });
  const prismatic = joints.some(isPrismatic);
  body.append(section("robot-data", "Measured data",
    h("p", { class: "muted", dataset: { maxPoints: String(DATA_POINTS) } },
      `Dataset ${job.dataset_id}${runs > 1 ? ` (the first of ${runs} runs)` : ""} as uploaded, before any filter: ` +
      `${plural(data.q.length, "joint")}, drawn ${data.t.length} samples.` + (prismatic ? " Prismatic joints in m and N." : "")),
    angleBox, data.tau ? torqueBox : h("p", {}, "The dataset has no torque.")));
  const series = data.q.map((_, j) => ({ label: name(j), color: PALETTE[j % PALETTE.length] }));
  // One axis for every joint: its unit names both when revolute and prismatic joints share it.
  const unit = (revolute, prismaticUnit) => {
    const kinds = new Set(data.q.map((_, j) => isPrismatic(joints[j])));
    return kinds.size > 1 ? `${revolute} and ${prismaticUnit}` : kinds.has(true) ? prismaticUnit : revolute;
  };
  lineChart(angleBox, { title: "Joint angles", xLabel: "t, s", yLabel: `q, ${unit("rad", "m")}`, series, data: [data.t, ...data.q] });
  if (data.tau) {
    lineChart(torqueBox, { title: "Joint torques", xLabel: "t, s", yLabel: `τ, ${unit("N·m", "N")}`, series, data: [data.t, ...data.tau] });
  }
}

function ratioInWords(estimate, prior) {
  if (!(estimate > 0) || !(prior > 0)) return "–";
  const ratio = estimate / prior;
  if (Math.abs(ratio - 1) < 0.005) return "the same";
  return ratio < 1 ? `${number(1 / ratio, 3)}× smaller` : `${number(ratio, 3)}× larger`;
}

function validationVerdict(estimate, prior) {
  if (!(estimate >= 0) || !(prior >= 0)) return "";
  const ratio = prior > 0 ? estimate / prior : Infinity;
  if (Math.abs(ratio - 1) < 0.005) return "The estimate predicts the validation run as well as the URDF's own values.";
  return ratio < 1
    ? `The estimate predicts the validation run ${number(1 / ratio, 3)}× better than the URDF's own values (${percent(estimate)} against ${percent(prior)}).`
    : `The URDF's own values predict the validation run better than the estimate (${percent(prior)} against ${percent(estimate)}).`;
}

async function validationSection(body, job, result) {
  if (!job.validation_dataset_id) {
    body.append(section("validation", "Validation",
      h("p", { id: "validation-none" }, "No validation run: name a run \u201cvalidation (held out)\u201d in the robot page's " +
        "Identify form (validation_dataset_ids in the API) to see how the estimate predicts data it was not fitted to.")));
    return;
  }
  const validation = await api(`/v1/jobs/${job.id}/validation?max_points=${JOINT_POINTS}`);
  const held = job.request?.validation_dataset_ids?.length || 1;
  const prior = validation.prior?.relative_error || [];
  const widest = Math.max(...validation.joints.map((joint) => joint.relative_error || 0), ...prior.map((value) => value || 0),
                          validation.overall_relative_error || 0) || 1;
  const bar = (value, kind) => h("span", { class: `bar ${kind}`, style: `width:${Math.max(0.5, (100 * (value || 0)) / widest)}%` });
  const bars = (estimate, urdf) => h("td", { class: "bars", "aria-hidden": "true" }, bar(estimate, "estimate"), bar(urdf, "prior"));
  // Each joint's error also in its unit (RMS of τ̂ − τ under the judge; the result's figures, first run).
  const rmsEstimate = result.validation?.rms_error || [], rmsPrior = result.validation?.prior?.rms_error || [];
  const withUnit = (fraction, rms, joint) => [percent(fraction),
    typeof rms === "number" ? h("span", { class: "muted rms" }, ` (${number(rms, 3)} ${torqueUnit(joint)})`) : null];
  const robotJoints = result.robot?.joints || [];
  const rows = validation.joints.map((joint, i) => h("tr", {
    dataset: { joint: joint.name, estimateError: String(joint.relative_error), priorError: String(prior[i]),
               estimateRms: String(rmsEstimate[i] ?? ""), priorRms: String(rmsPrior[i] ?? "") } },
    h("th", { scope: "row" }, joint.name),
    h("td", { class: "number" }, withUnit(joint.relative_error, rmsEstimate[i], robotJoints[joint.joint - 1])),
    h("td", { class: "number" }, withUnit(prior[i], rmsPrior[i], robotJoints[joint.joint - 1])),
    bars(joint.relative_error, prior[i]),
    h("td", { class: "number" }, ratioInWords(joint.relative_error, prior[i]))));
  const overall = validation.overall_relative_error, overallPrior = validation.prior?.overall_relative_error;
  const charts = jointTorqueCharts("validation", validation, result.robot?.joints || [],
                                   { measuredLabel: "measured (filtered)", modelLabel: "predicted" });
  body.append(section("validation", "Validation: predicting a second run",
    h("p", { id: "validation-verdict" }, validationVerdict(overall, overallPrior)),
    h("p", { class: "muted", dataset: { maxPoints: String(JOINT_POINTS) } },
      `Dataset ${job.validation_dataset_id}${held > 1 ? ` (the first of ${held} validation runs; the error at a glance takes all ${held})` : ""}, ` +
      `through the identification's filters: ${validation.samples} filtered samples. ` +
      "Error per joint: ‖τ̂ − τ‖ / ‖τ‖ and, in brackets, the RMS of τ̂ − τ, predicted by the estimate and by the URDF's own " +
      `inertial and friction values, ${judgeInWords(result.judge)}.`),
    h("div", { class: "scroll" }, h("table", { id: "validation-table", class: "data" },
      h("thead", {}, h("tr", {},
        h("th", { scope: "col" }, "Joint"),
        h("th", { scope: "col", class: "number" }, h("span", { class: "swatch-box estimate" }), " Estimate's error"),
        h("th", { scope: "col", class: "number" }, h("span", { class: "swatch-box prior" }), " URDF values' error"),
        h("th", { scope: "col", class: "bars" }, h("span", { class: "visually-hidden" }, "Bars")),
        h("th", { scope: "col", class: "number" }, "Estimate's error is"))),
      h("tbody", {}, rows),
      h("tfoot", {}, h("tr", { dataset: { estimateError: String(overall), priorError: String(overallPrior) } },
        h("th", { scope: "row" }, "all joints"), h("td", { class: "number" }, percent(overall)),
        h("td", { class: "number" }, percent(overallPrior)), bars(overall, overallPrior),
        h("td", { class: "number" }, ratioInWords(overall, overallPrior)))))),
    h("h3", {}, "Per joint: measured and predicted"),
    charts));
  charts.draw();
}

/** The sections of a robot identification's page. */
export async function robotIdentificationSections(body, job, drawOrExplain) {
  const result = job.result;
  body.append(glance(job, result), baseParameterSection(result), correlationSection(result), frictionSection(result),
              consistencySection(result), linkSection(result), identifiabilitySection(result));
  await drawOrExplain("Torque fit per joint", () => fitSection(body, job, result));
  if (job.state === "succeeded") await drawOrExplain("Validation", () => validationSection(body, job, result));
  if (job.dataset_id) await drawOrExplain("Measured data", () => measuredDataSection(body, job, result));
}

// ---- excitation -------------------------------------------------------------------------------

export async function excitationSections(body, job, drawOrExplain) {
  const result = job.result;
  const design = result.coefficients || {};
  const robot = await api(`/v1/robots/${job.robot_id}`).catch(() => null);
  const names = design.joints || robot?.joints.map((joint) => joint.name) || [];
  const condition = design.criterion === "condition" || !design.criterion;
  body.append(section("excitation", "Excitation design",
    facts([
      ["Robot", h("a", { href: robotPath(job.robot_id), id: "robot-link" }, design.robot || robot?.name || job.robot_id)],
      ["Condition number", h("span", { id: "excitation-condition", dataset: { value: String(result.condition_number) } },
        condition && design.initial_criterion_value !== undefined
          ? `${number(design.initial_criterion_value, 4)} → ${number(result.condition_number, 4)}`
          : number(result.condition_number, 4))],
      ["Criterion", design.criterion ? `${design.criterion === "logdet" ? "maximise log det" : "minimise the condition number"} of the base regressor` +
                                       (design.log_det !== undefined ? ` (log det ${number(design.log_det, 4)})` : "") : null],
      ["Base parameters excited", design.base_parameters !== undefined ? String(design.base_parameters) : null],
      ["Trajectory", `${number(design.period, 4)} s period, ${plural(design.harmonics, "harmonic")}, ` +
                     `${result.periods !== undefined ? plural(result.periods, "period") + ", " : ""}${result.samples} samples every ${number(result.dt, 3)} s`],
      ["Start pose", design.ramp
        ? h("span", { id: "excitation-ramp" }, `(${design.ramp.pose.map((value) => number(value, 3)).join(", ")}); ` +
            `ramps of ${number(result.ramp_duration ?? design.ramp.duration, 3)} s to the trajectory and back`)
        : null],
      ["Torque", design.limits?.torque
        ? `of ${design.limits.torque_model || "the URDF's"} parameters; ` +
          (design.torque_scale < 1 ? `its limits cut the motion to ${number(design.torque_scale, 3)} of what the other limits allow`
                                   : "its limits do not bind")
        : null],
      ["Search", design.evaluations !== undefined
        ? `${design.evaluations} evaluations in ${number(design.wall_seconds, 3)} s, stopped: ${design.message || design.termination}` : null],
      ["Seed", design.seed !== undefined ? String(design.seed) : null],
      ["Trajectory to run", result.dataset_id
        ? downloadLink(`/v1/datasets/${result.dataset_id}?format=csv`, `${result.dataset_id} as CSV (t, q, qd, qdd)`, { id: "excitation-csv" })
        : null],
    ]),
    h("p", { class: "muted" }, "Next: run it on the robot, log t, q and τ, upload the log as a dataset and identify it with this robot_id."),
    design.active_limits?.length
      ? [h("h3", {}, "Limits it reaches"),
         h("div", { class: "scroll" }, h("table", { id: "active-limits", class: "data" },
           h("thead", {}, h("tr", {}, ["Joint", "Limit", "Peak", "Limit value"].map((label, i) => h("th", { scope: "col", class: i > 1 ? "number" : null }, label)))),
           h("tbody", {}, design.active_limits.map((limit) => h("tr", {},
             h("th", { scope: "row" }, limit.joint), h("td", {}, limit.kind),
             h("td", { class: "number" }, number(limit.peak, 4)), h("td", { class: "number" }, number(limit.limit, 4)))))))]
      : null));
  if (design.usage) body.append(limitUsage(design, names, robot));
  if (result.dataset_id) await drawOrExplain("Joint angles", () => excitationCharts(body, result, design, names, robot));
}

// What each joint reaches against each of its limits (the design's measure, over one period).
const LIMIT_COLUMNS = [
  ["velocity", "q̇", (joint) => (isPrismatic(joint) ? "m/s" : "rad/s")],
  ["acceleration", "q̈", (joint) => (isPrismatic(joint) ? "m/s²" : "rad/s²")],
  ["jerk", "jerk", (joint) => (isPrismatic(joint) ? "m/s³" : "rad/s³")],
  ["torque", "τ", torqueUnit],
];

function limitUsage(design, names, robot) {
  const share = (value) => (typeof value === "number" ? percent(value, 3) : "no limit");
  const cell = (kind, j, unit) => {
    const peak = design.peaks?.[kind]?.[j], limit = design.limits?.[kind]?.[j], used = design.usage?.[kind]?.[j];
    return h("td", { class: "number", dataset: { kind, usage: typeof used === "number" ? String(used) : "" },
                     title: typeof limit === "number" ? `limit ${number(limit, 4)} ${unit}` : "no limit" },
      typeof peak === "number" ? `${number(peak, 3)} ${unit} (${share(used)})` : "—");
  };
  const margin = (j) => {
    const low = design.usage?.lower?.[j], high = design.usage?.upper?.[j];
    const values = [low, high].filter((value) => typeof value === "number");
    return values.length ? percent(Math.max(...values), 3) : "no limit";
  };
  return section("excitation-limits", "Limits per joint",
    h("p", { class: "muted" },
      "What the design reaches over a period, and in brackets the share of each limit it uses. Positions: the share of the room " +
      `between the mean pose and the nearer limit (the URDF's, less ${number(design.limits?.position_margin ?? 0, 3)}).`),
    h("div", { class: "scroll" }, h("table", { id: "excitation-usage", class: "data" },
      h("thead", {}, h("tr", {}, ["Joint", "Position room", ...LIMIT_COLUMNS.map(([, label]) => `Peak |${label}|`)].map(
        (label, i) => h("th", { scope: "col", class: i > 0 ? "number" : null }, label)))),
      h("tbody", {}, names.map((name, j) => h("tr", {},
        h("th", { scope: "row" }, name),
        h("td", { class: "number", dataset: { kind: "position" } }, margin(j)),
        LIMIT_COLUMNS.map(([kind, , unit]) => cell(kind, j, unit(robot?.joints[j])))))))));
}

async function excitationCharts(body, result, design, names, robot) {
  const data = await api(`/v1/datasets/${result.dataset_id}/data?max_points=${JOINT_POINTS}`);
  const ramp = result.ramp_duration > 0 ? ` The first and last ${number(result.ramp_duration, 3)} s ramp from the start pose and back.` : "";
  const torque = result.torque;  // the limits' model's torque at ≤ 1000 samples (older results: none)
  const quantities = [
    { key: "q", symbol: "q", id: "excitation-angles", title: "Joint angles", values: data.q, t: data.t, unit: (joint) => (isPrismatic(joint) ? "m" : "rad"),
      limits: (j) => [["lower", design.limits?.lower?.[j]], ["upper", design.limits?.upper?.[j]]],
      words: "each joint's angle; dashed: the design's limits (the URDF's, less a margin)." },
    { key: "qd", symbol: "q̇", id: "excitation-velocities", title: "Joint velocities", values: data.qd, t: data.t, unit: LIMIT_COLUMNS[0][2], symmetric: "velocity",
      words: "each joint's velocity; dashed: ± its velocity limit." },
    { key: "qdd", symbol: "q̈", id: "excitation-accelerations", title: "Joint accelerations", values: data.qdd, t: data.t, unit: LIMIT_COLUMNS[1][2], symmetric: "acceleration",
      words: "each joint's acceleration; dashed: ± its acceleration limit." },
    { key: "tau", symbol: "τ", id: "excitation-torques", title: "Joint torques", values: torque?.tau, t: torque?.t, unit: torqueUnit, symmetric: "torque",
      words: `the torque ${design.limits?.torque_model === "given parameters" ? "the given model" : "the URDF's parameters"} ` +
             "predict for it; dashed: ± each joint's torque limit." },
  ];
  for (const quantity of quantities) {
    if (!quantity.values || !quantity.t) continue;
    const boxes = quantity.values.map((_, j) =>
      h("div", { id: `chart-excitation-${quantity.key}-${j + 1}`, dataset: { jointName: names[j] || `joint ${j + 1}` } }));
    body.append(section(quantity.id, quantity.title,
      h("p", { class: "muted", dataset: { maxPoints: String(JOINT_POINTS) } },
        `Over the run (drawn: ${quantity.t.length} points), ${quantity.words}${ramp}`),
      h("div", { class: "grid joints" }, boxes)));
    quantity.values.forEach((values, j) => {
      const series = [{ label: `${quantity.key}${j + 1}`, color: PALETTE[j % PALETTE.length] }];
      const columns = [quantity.t, values];
      const limit = quantity.symmetric ? design.limits?.[quantity.symmetric]?.[j] : undefined;
      const bounds = quantity.limits ? quantity.limits(j) : [["−limit", typeof limit === "number" ? -limit : null], ["+limit", limit]];
      for (const [label, value] of bounds) {
        if (typeof value !== "number") continue;  // null: no limit
        series.push({ label, color: "#777", dash: [4, 4], width: 1 });
        columns.push(quantity.t.map(() => value));
      }
      lineChart(boxes[j], { title: names[j] || `joint ${j + 1}`, xLabel: "t, s", yLabel: `${quantity.symbol}, ${quantity.unit(robot?.joints[j])}`,
                            height: 200, sync: "excitation", legend: false, series, data: columns });
    });
  }
}

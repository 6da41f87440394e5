// payload_job.js — the sections of a payload identification's page (/jobs/{id} of kind payload_identification):
// the payload card — whether the runs found a payload, its mass, centre of mass and inertia about it with their
// standard errors (or "given"), what the runs leave undetermined and the warnings, the torque error without and
// with it, the URDF with it mounted, and a picture of the centre of mass on the flange (the tip link's x–y plane
// from above and x–z from the side, the point with two standard errors around it) — then the torque with and
// without the payload beside the measured, per joint (/fit; /validation with a validation run), and the run.
import { api, downloadLink } from "./api.js";
import { facts, h, number, percent, plural, section } from "./dom.js";
import { jobPath, robotPath } from "./paths.js";
import { JOINT_POINTS, againWithPhysical, judgeInWords, jointTorqueCharts, measuredDataSection } from "./robot_job.js";

const ENTRIES = ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"];
const AXES = ["x", "y", "z"];
const isNumber = (value) => typeof value === "number" && Number.isFinite(value);

// ---- the values -------------------------------------------------------------------------------

function verdict(result) {
  const mass = `${number(result.mass, 4)} ± ${number(result.mass_std_error, 2)} kg`;
  if (result.detected) {
    return h("p", { id: "payload-verdict", class: "verdict", dataset: { detected: "true" } },
      h("strong", {}, `A payload of ${result.given?.mass ? `${number(result.mass, 4)} kg (given)` : mass}`),
      ` on ${result.robot?.tip_link ?? "the tip link"}.`);
  }
  return h("p", { id: "payload-verdict", class: "verdict", dataset: { detected: "false" } },
    h("strong", {}, "No payload: "), `the mass, ${mass}, is not distinguishable from 0 (within two standard errors), ` +
    "so no centre of mass or inertia is reported. A run without a payload answers this way; it is not an error.");
}

/** One row of the values table: the estimate and its standard error, or why there is none. */
function valueRow(key, label, value, error, given, digits = 4) {
  const why = given ? "given" : !isNumber(value) ? "not reported" : error === null || error === undefined ? "not determined" : null;
  return h("tr", { dataset: { quantity: key, estimate: isNumber(value) ? String(value) : "", stdError: isNumber(error) ? String(error) : "" } },
    h("th", { scope: "row" }, label),
    h("td", { class: "number" }, number(value, digits)),
    h("td", { class: "number" }, why ? h("span", { class: "muted" }, why) : `± ${number(error, 2)}`));
}

function valuesTable(result) {
  const mm = (value) => (isNumber(value) ? 1000 * value : value);
  const com = result.centre_of_mass || [], comErrors = result.centre_of_mass_std_errors || [];
  const inertia = result.inertia_about_com || {}, inertiaErrors = result.inertia_std_errors || {};
  const givenCom = Array.isArray(result.given?.centre_of_mass);
  return h("div", { class: "scroll" }, h("table", { id: "payload-values", class: "data compact" },
    h("caption", {}, "The payload in the tip link's frame: its centre of mass from the link's origin, its inertia about the centre of mass in the link's axes"),
    h("thead", {}, h("tr", {}, ["", "Estimate", "Std error"].map((label, i) => h("th", { scope: "col", class: i ? "number" : null }, label)))),
    h("tbody", {},
      valueRow("mass", "Mass, kg", result.mass, result.mass_std_error, isNumber(result.given?.mass)),
      AXES.map((axis, i) => valueRow(`com_${axis}`, `Centre of mass ${axis}, mm`, mm(com[i]), mm(comErrors[i]), givenCom, 3)),
      ENTRIES.map((entry) => valueRow(entry, `I${entry.slice(1)}, kg·m²`, inertia[entry], inertiaErrors[entry], false, 3)))));
}

function torqueErrors(result) {
  const fit = result.fit || {}, validation = result.validation;
  return [
    ["Torque error on the run", [h("span", { id: "payload-fit-arm" }, percent(fit.arm_only_error)), " with the arm alone, ",
      h("span", { id: "payload-fit-with" }, percent(fit.with_payload_error)), " with the payload (filtered, relative)"]],
    ["Held-out runs", validation
      ? [h("span", { id: "payload-validation-arm" }, percent(validation.arm_only?.overall_relative_error)), " with the arm alone, ",
         h("span", { id: "payload-validation-with" }, percent(validation.with_payload?.overall_relative_error)), ` with the payload, ${judgeInWords(result.judge)}`]
      : null],
  ];
}

/** Whether the payload is a real rigid body, and what the physical fit (physical: true) did. */
function realBody(result) {
  if (!result.detected) return null;
  const physical = result.physical;
  const fit = physical
    ? physical.least_squares_consistent
      ? " (asked for: the least-squares payload was one already, unchanged)"
      : ` (asked for: the fit over real bodies costs ${percent(physical.relative_cost_increase)} more squared residual)`
    : "";
  if (result.consistent) return h("span", { id: "payload-consistent", dataset: { consistent: "true" } }, `yes${fit}`);
  const findings = result.consistency_findings || [];
  return h("span", { id: "payload-consistent", dataset: { consistent: "false" } },
    `no: ${findings[0]?.replace(/^the payload: /, "") || "not a possible rigid body"}` +
    (findings.length > 1 ? ` (and ${plural(findings.length - 1, "more finding")}: see the warnings)` : ""));
}

/**
 * The URDF with the payload mounted: a download when it is a real body; when it is not (a URDF holds no such
 * link, a simulator refuses it), the same identification asked for a real body instead.
 */
function urdfActions(job, result) {
  if (!result.detected) return null;
  if (result.consistent !== false || job.request?.physical) {
    return h("p", { class: "actions" },
      downloadLink(`/v1/jobs/${job.id}/urdf`, "Download the URDF with the payload", { id: "payload-urdf", class: "button" }),
      h("span", { class: "muted" }, "The robot's document with the payload as a fixed link on the tip link."));
  }
  return h("div", { id: "payload-not-real", class: "actions" },
    h("p", {}, h("strong", {}, "Not a real rigid body: "), "least squares does not know that a payload is a body, and " +
      "this one's inertia is none a distribution of mass could have; simulators refuse or misbehave on such a link. The same " +
      "identification over real bodies only fits the runs as closely as that allows."),
    h("p", {}, againWithPhysical(job, "payload-physical", "Identify again as a real body")));
}

function payloadCard(job, result) {
  const arm = result.arm_job_id
    ? ["identified by ", h("a", { href: jobPath(result.arm_job_id), id: "arm-job-link" }, result.arm_job_id), " (its point)"]
    : "the URDF's own values (no arm_job_id)";
  const undetermined = result.undetermined || [];
  return section("payload", "Payload",
    verdict(result),
    h("div", { class: "payload-card" },
      h("div", {},
        valuesTable(result),
        facts([
          ["Robot", [h("a", { href: robotPath(job.robot_id), id: "robot-link" }, result.robot?.name || job.robot_id),
                     `, payload on ${result.robot?.tip_link ?? "its tip link"}`]],
          ["The arm", arm],
          ...torqueErrors(result),
          ["A real body", realBody(result)],
          ["Undetermined", undetermined.length
            ? h("ul", { id: "payload-undetermined", class: "names" }, undetermined.map((name) => h("li", {}, h("code", {}, name))))
            : h("span", { id: "payload-undetermined" }, "none: the runs determine all ten parameters")],
          ["Standard errors", result.variance_inflation > 1.0001
            ? `widened ×${number(Math.sqrt(result.variance_inflation), 3)}: the residual is correlated over time`
            : "from the filtered residual"],
          ["Fitted", h("span", { id: "payload-filters" }, `${plural(result.torque_joints?.length ?? 0, "joint")}, ${result.rows} rows; comparison low-pass ` +
                     `${number(result.filters?.comparison_cutoff_hz, 3)} Hz` +
                     (result.filters?.chosen_by_held_out
                       ? ` (chosen by held-out error among ${result.filters.candidates.length}: ` +
                         `${number(100 * result.filters.held_out_error, 3)} % of the arm's residual)`
                       : ""))],
        ]),
        urdfActions(job, result)),
      h("figure", { id: "payload-figure" }, comPicture(result),
        h("figcaption", { class: "muted small" },
          "The centre of mass on the flange: from above (the tip link's x–y plane) and from the side (x–z). The circle is a " +
          "scale around the link's origin, not the flange's real size; the shaded ellipses span two standard errors."))),
    h("h3", {}, "Warnings"),
    result.warnings?.length
      ? h("ul", { class: "warnings", id: "payload-warnings" }, result.warnings.map((warning) => h("li", {}, warning)))
      : h("p", { id: "payload-warnings" }, "None."));
}

// ---- the centre of mass on the flange ---------------------------------------------------------

const SVG = "http://www.w3.org/2000/svg";

/** An SVG element: svg("circle", {cx: 1}, children...). */
function svg(tag, attributes = {}, ...children) {
  const element = document.createElementNS(SVG, tag);
  for (const [name, value] of Object.entries(attributes)) {
    if (value !== undefined && value !== null) element.setAttribute(name, String(value));
  }
  for (const child of children.flat()) {
    if (child !== null && child !== undefined) element.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return element;
}

/** The smallest of 10, 20, 25, 50 × a power of ten mm at or above `metres`, in metres. */
function roundRadius(metres) {
  const power = 10 ** Math.floor(Math.log10(metres * 1000));
  const step = [1, 2, 2.5, 5, 10].find((factor) => factor * power >= metres * 1000 - 1e-9);
  return (step * power) / 1000;
}

/**
 * Two views of the flange on one scale: from above (x right, y up) and from the side (x right, z up). The
 * centre of mass is a point with an ellipse of two standard errors per axis; the circle (top) and the plate
 * (side) have a round radius that holds it.
 */
function comPicture(result) {
  const c = result.centre_of_mass || [], e = result.centre_of_mass_std_errors || [];
  const has = c.length === 3 && c.every(isNumber);
  const sigma = (i) => (isNumber(e[i]) ? e[i] : 0);
  const reach = has ? Math.max(...AXES.map((_, i) => Math.abs(c[i]) + 2 * sigma(i))) : 0;
  const radius = roundRadius(Math.max(reach, 0.02));
  const size = 260, gap = 30, half = size / 2, scale = (half - 26) / (1.2 * radius);  // px per metre
  const panel = (index, title, horizontal, vertical, u, v, su, sv, plate) => {
    const x0 = index * (size + gap) + half, y0 = half + 10;
    const px = (value) => x0 + scale * value, py = (value) => y0 - scale * value;
    const length = scale * 1.2 * radius;
    return svg("g", { class: `view view-${horizontal}${vertical}` },
      svg("text", { x: index * (size + gap) + 4, y: 14, "font-weight": 600 }, title),
      plate,
      svg("line", { class: "axis", x1: x0, y1: y0, x2: x0 + length, y2: y0 }),
      svg("line", { class: "axis", x1: x0, y1: y0, x2: x0, y2: y0 - length }),
      svg("text", { x: x0 + length - 8, y: y0 + 14 }, horizontal),
      svg("text", { x: x0 + 5, y: y0 - length + 8 }, vertical),
      has
        ? [svg("line", { class: "lever", x1: x0, y1: y0, x2: px(u), y2: py(v) }),
           svg("ellipse", { class: "sigma", cx: px(u), cy: py(v), rx: Math.max(scale * 2 * su, 0.5), ry: Math.max(scale * 2 * sv, 0.5) }),
           svg("circle", { class: "com", cx: px(u), cy: py(v), r: 4, "data-u": u, "data-v": v,
                           "data-axes": `${horizontal}${vertical}` },
             svg("title", {}, `centre of mass: ${horizontal} ${number(1000 * u, 3)} mm, ${vertical} ${number(1000 * v, 3)} mm`))]
        : null);
  };
  const top = panel(0, "From above: x–y", "x", "y", c[0], c[1], sigma(0), sigma(1),
    svg("circle", { class: "plate", cx: half, cy: half + 10, r: scale * radius }));
  const side = panel(1, "From the side: x–z", "x", "z", c[0], c[2], sigma(0), sigma(2),
    svg("rect", { class: "plate", x: size + gap + half - scale * radius, y: half + 10, width: 2 * scale * radius, height: 6 }));
  const note = [
    svg("text", { x: 4, y: size + 34 }, has
      ? `The point: (${c.map((value) => number(1000 * value, 3)).join(", ")}) mm`
      : "No centre of mass: no payload detected."),
    svg("text", { x: 4, y: size + 56 }, `Circle: ${number(1000 * radius, 3)} mm around the tip link's origin.`)];
  return svg("svg", { class: "flange", id: "payload-com", viewBox: `0 0 ${2 * size + gap} ${size + 66}`, role: "img",
                      "aria-label": has ? `The centre of mass at x ${number(1000 * c[0], 3)}, y ${number(1000 * c[1], 3)}, ` +
                                          `z ${number(1000 * c[2], 3)} mm from the tip link's origin`
                                        : "No payload detected: no centre of mass",
                      "data-radius": radius },
    svg("defs", {}, svg("marker", { id: "flange-arrow", viewBox: "0 0 10 10", refX: 9, refY: 5, markerWidth: 6, markerHeight: 6,
                                    orient: "auto-start-reverse" }, svg("path", { d: "M 0 0 L 10 5 L 0 10 z", fill: "#5a5a5a" }))),
    top, side, note);
}

// ---- the torque with and without the payload --------------------------------------------------

async function torqueSection(body, job, view) {
  const validation = view === "validation";
  const fit = await api(`/v1/jobs/${job.id}/${view}?max_points=${JOINT_POINTS}`);
  const id = `payload-${view}`;
  const charts = jointTorqueCharts(id, fit, [], { measuredLabel: "measured (filtered)", modelLabel: "with the payload",
                                                  extra: { field: "arm_only", label: "the arm alone" } });
  const rows = fit.joints.map((joint) => h("tr", { dataset: { joint: joint.name, withPayload: String(joint.relative_error),
                                                              armOnly: String(joint.arm_only_relative_error) } },
    h("th", { scope: "row" }, joint.name),
    h("td", { class: "number" }, percent(joint.arm_only_relative_error)),
    h("td", { class: "number" }, percent(joint.relative_error))));
  body.append(section(id, validation ? "Validation: a held-out run with and without the payload" : "Torque with and without the payload",
    h("p", { class: "muted", dataset: { maxPoints: String(JOINT_POINTS) } },
      `Dataset ${validation ? job.validation_dataset_id : job.dataset_id}: the measured torque beside what the arm predicts ` +
      `with the payload and without it, ${judgeInWords(fit.judge)}; ${fit.samples} samples, drawn ${fit.t.length}. ` +
      `Overall ‖τ̂ − τ‖ / ‖τ‖: ${percent(fit.arm_only?.overall_relative_error)} with the arm alone, ` +
      `${percent(fit.overall_relative_error)} with the payload.`),
    h("div", { class: "scroll" }, h("table", { id: `${id}-table`, class: "data compact" },
      h("thead", {}, h("tr", {}, ["Joint", "Arm alone", "With the payload"].map((label, i) => h("th", { scope: "col", class: i ? "number" : null }, label)))),
      h("tbody", {}, rows))),
    charts));
  charts.draw();
}

/** The sections of a payload identification's page. */
export async function payloadSections(body, job, drawOrExplain) {
  const result = job.result;
  body.append(payloadCard(job, result));
  await drawOrExplain("Torque with and without the payload", () => torqueSection(body, job, "fit"));
  if (job.validation_dataset_id) await drawOrExplain("Validation", () => torqueSection(body, job, "validation"));
  if (job.dataset_id) await drawOrExplain("Measured data", () => measuredDataSection(body, job, result));
}

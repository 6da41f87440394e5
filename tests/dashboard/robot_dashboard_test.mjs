// robot_dashboard_test.mjs — the dashboard's robot pages end to end in headless Chromium:
// make two runs of a 7-joint arm with the real binary (`manipid excitation`, `manipid torque`
// with noise, seeds 1 and 2), start `manipid serve --port 0`, upload the URDF with the robots
// page's form, one run by the API and the other as a CSV file through the identify form, name
// them training and validation run, identify from the robot's page (keyboard), then check the
// identification's page against the API: the base-parameter table (rows, numbers, filter,
// sort), the correlation map, friction, the consistency verdict, one fit chart per joint with
// the API's point count, the friction curves (points and law against the API's), the validation
// errors per joint beside the URDF's, the run's measured angles and torques, charts that keep
// their axes (the legend, zoom across small multiples, the plot switch, a resize), the identified
// URDF's download; then the robots list and the robot's page from the header, an excitation designed
// from the robot's page, the home page's way to the robots and the job list's robot names,
// keyboard reach, a narrow screen, a clean console, and that the binary serves the web/src it
// was built from. Screenshots go to ARTIFACT_DIR.
//
//   node tests/dashboard/robot_dashboard_test.mjs path/to/manipid ARTIFACT_DIR
//
// Exit 0: pass; 1: a check failed; 77: skipped (no chromium, or playwright-core not installed).
import { execFileSync } from "node:child_process";
import { mkdirSync, mkdtempSync, readFileSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import path from "node:path";
import { axisRange, check, chromiumOrSkip, dragAcross, failed, json, launch, newPage, overflow, root, startServer, stopServer,
         tabUntil } from "./support.mjs";

const [given, artifacts = path.join(tmpdir(), "manipid-dashboard-artifacts")] = process.argv.slice(2);
const binary = given && path.resolve(given);
if (!binary) { console.error("usage: robot_dashboard_test.mjs path/to/manipid [ARTIFACT_DIR]"); process.exit(2); }
const chromium = chromiumOrSkip();

const URDF = path.join(root, "examples/robots/panda_like.urdf");
const JOINTS = 7;
const shot = (name) => path.join(artifacts, name);
/** The number a cell shows ("0.0632 %", "178 % (not determined)", "-9.94394e-4"), or NaN for "–". */
const shown = (text) => parseFloat(text);
const close = (a, b, relative) => Math.abs(a - b) <= relative * Math.abs(b);

const workdir = mkdtempSync(path.join(tmpdir(), "manipid-robot-dashboard-"));
mkdirSync(artifacts, { recursive: true });

// Two noisy runs of one excitation: the identification's and the validation's.
const run = (...args) => execFileSync(binary, args, { cwd: workdir, stdio: ["ignore", "ignore", "pipe"] });
// A budget of evaluations, not seconds: the same excitation (and a physically consistent estimate, whose
// URDF the page downloads) on every machine, loaded or not.
run("excitation", "--robot", URDF, "--period", "10", "--harmonics", "5", "--duration", "20", "--max-evaluations", "400",
    "--max-seconds", "600", "--out", "exc.csv");
for (const seed of [1, 2]) {
  run("torque", "--robot", URDF, "--in", "exc.csv", "--with-states", "--noise-tau-relative", "0.01", "--seed", String(seed),
      "--out", `run${seed}.csv`);
}

const { server, url } = await startServer(binary, path.join(workdir, "jobs.db"));
const browser = await launch(chromium);
const consoleErrors = [];
try {
  const page = await newPage(browser, consoleErrors);

  // First: the binary serves the web/src it was built from. A stale build would test old pages
  // (api/CMakeLists.txt re-embeds only when a file it lists changes).
  const sources = JSON.parse(/SOURCES = (\[[^\]]*\])/.exec(readFileSync(path.join(root, "web/tools/embed_web.py"), "utf8"))[1]);
  const stale = [];
  for (const name of sources) {
    const served = await fetch(`${url}${name === "index.html" ? "/" : `/assets/${name}`}`).then((response) => response.text());
    if (served !== readFileSync(path.join(root, "web/src", name), "utf8")) stale.push(name);
  }
  if (!check(stale.length === 0, `the binary embeds today's web/src${stale.length ? `; stale: ${stale.join(", ")}` : ""}`)) {
    throw new Error("the binary serves an older web/src: touch web/tools/embed_web.py and build again");
  }

  // ---- the robots page from the header, by keyboard; upload the URDF with its form ----------
  await page.goto(`${url}/`);
  await page.waitForSelector("#paper-form");
  check(await tabUntil(page, () => document.activeElement?.matches?.('header nav a[href="/robots"]')),
        "the header's Robots link is reachable with Tab");
  await page.keyboard.press("Enter");
  await page.waitForURL(/\/robots$/);
  await page.waitForSelector("body[data-ready=true] #robot-upload");
  check((await page.textContent("#robots tbody")).includes("No robots yet"), "an empty robots list says so");
  await page.setInputFiles("#u-file", URDF);
  check(await tabUntil(page, () => document.activeElement?.id === "robot-upload-submit"), "the upload button is reachable with Tab");
  await page.keyboard.press("Enter");
  await page.waitForURL(/\/robots\/rb_[0-9a-f]+$/, { timeout: 30000 });
  const robotId = page.url().split("/").pop();
  const robot = await json(`${url}/v1/robots/${robotId}`);
  check(robot.joints.length === JOINTS, `the form uploaded ${robot.name} with ${robot.joints.length} joints`);
  await page.waitForSelector("body[data-ready=true] #identify-form");
  check(await page.locator("#robot-joints tbody tr").count() === JOINTS, "the robot's page lists its 7 joints");
  const firstJoint = robot.joints[0];
  check((await page.textContent(`#robot-joints tr[data-joint="${firstJoint.name}"]`)).includes(`${firstJoint.limits.velocity} rad/s`),
        `... with their limits (${firstJoint.name}: ${firstJoint.limits.velocity} rad/s)`);

  // ---- one run stored by the API, one added from the disk; identify from the robot's page ------
  const validationRun = await json(`${url}/v1/datasets?name=run2`, { method: "POST", headers: { "Content-Type": "text/csv" },
                                                                    body: readFileSync(path.join(workdir, "run2.csv")) });
  await page.reload();
  await page.waitForSelector("body[data-ready=true] #identify-form");
  const storedRow = `#i-runs tr[data-dataset-id="${validationRun.id}"]`;
  check(await page.locator("#i-runs tbody tr").count() === 1 && (await page.textContent(`${storedRow} th`)).includes("run2") &&
        (await page.textContent(storedRow)).includes(String(validationRun.samples)) &&
        await page.inputValue(`${storedRow} select`) === "train",
        `the identify form lists the stored run (run2, ${validationRun.samples} samples), a training run by default`);
  // No training run: the form says so and submits nothing.
  await page.selectOption(`${storedRow} select`, "unused");
  await page.click("#identify-submit");
  check(/at least one training run/.test(await page.textContent("#identify-form .form-status")) && page.url().endsWith(`/robots/${robotId}`) &&
        await page.getAttribute(`${storedRow} select`, "aria-invalid") === "true",
        `no training run: "${await page.textContent("#identify-form .form-status")}", nothing submitted`);
  // A CSV from the disk (an in-memory file here): listed first, to be uploaded on Identify.
  await page.setInputFiles("#i-files", { name: "run1.csv", mimeType: "text/csv", buffer: readFileSync(path.join(workdir, "run1.csv")) });
  const fileRow = '#i-runs tr[data-file="run1.csv"]';
  check(await page.locator("#i-runs tbody tr").count() === 2 && await page.getAttribute("#i-runs tbody tr:first-child", "data-file") === "run1.csv" &&
        await page.inputValue(`${fileRow} select`) === "train" && (await page.textContent(fileRow)).includes("uploaded on Identify"),
        "the added file is listed first, as a training run, to upload on Identify");
  await page.selectOption(`${storedRow} select`, "validation");
  await page.locator("#identify-form").screenshot({ path: shot("identify-form.png") });
  await page.focus("#identify-submit");
  await page.keyboard.press("Enter");
  await page.waitForURL(/\/jobs\/job_[0-9a-f]+$/, { timeout: 60000 });
  const jobId = page.url().split("/").pop();
  await page.waitForSelector("body[data-ready=true]", { timeout: 240000 });
  const job = await json(`${url}/v1/jobs/${jobId}`);
  const measured = await json(`${url}/v1/datasets/${job.request.dataset_ids?.[0]}`);
  check(measured.name === "run1.csv" && measured.samples === validationRun.samples && measured.joints === JOINTS && measured.has_torque,
        `the form uploaded the file as a dataset named run1.csv (${measured.samples} samples, 7 joints and torque)`);
  check(job.request.robot_id === robotId && JSON.stringify(job.request.dataset_ids) === JSON.stringify([measured.id]) &&
        JSON.stringify(job.request.validation_dataset_ids) === JSON.stringify([validationRun.id]) &&
        JSON.stringify(job.request.friction) === JSON.stringify(["viscous", "coulomb"]),
        "the form asked for robot, the file as training run, the stored run as validation run, and viscous + Coulomb friction");
  check(await page.getAttribute("body", "data-job-state") === "succeeded" && job.state === "succeeded", `job ${jobId} reached succeeded on its page`);
  check(job.kind === "robot_identification", "the job is a robot_identification");
  check((await page.textContent("#job-state")).trim() === "succeeded", "the state badge says succeeded");
  const result = job.result;

  // ---- base parameters -----------------------------------------------------------------------
  const rows = page.locator("#base-table tbody tr");
  check(await rows.count() === result.base_parameters.length && result.base_parameters.length > 40,
        `base-parameter table: ${result.base_parameters.length} rows, as many as the result's base_parameters`);
  const table = await page.$$eval("#base-table tbody tr", (trs) => trs.map((tr) => ({
    name: tr.dataset.name, estimate: tr.dataset.estimate, stdError: tr.dataset.stdError, relative: tr.dataset.relative,
    quality: tr.dataset.quality, shown: [...tr.querySelectorAll("td.number")].slice(1).map((td) => td.textContent) })));
  const same = (attribute, value) => (value === null ? attribute === "" : Number(attribute) === value);
  const exact = result.base_parameters.every((p, i) => table[i].name === p.name && same(table[i].estimate, p.estimate) &&
    same(table[i].stdError, p.std_error) && same(table[i].relative, p.relative_std_error));
  check(exact, "every row holds the result's name, estimate, standard error and relative σ exactly (in order)");
  const readable = result.base_parameters.every((p, i) => close(shown(table[i].shown[0]), p.estimate, 1e-5) &&
    close(shown(table[i].shown[1]), p.std_error, 6e-3) && close(shown(table[i].shown[2]) / 100, p.relative_std_error, 6e-3));
  check(readable, "... and shows them to 6, 3 and 3 significant digits (relative σ in %)");
  check(table.filter((row) => row.quality === "unexcited").length === (result.unexcited || []).length,
        `unexcited rows marked: ${(result.unexcited || []).length}`);
  const long = result.base_parameters.findIndex((p) => p.name.split(/ (?=[+-] )/).length > 4);
  if (check(long >= 0, "a long base parameter (more than four terms) exists to elide")) {
    const row = page.locator(`#base-table tbody tr[data-index="${long + 1}"]`);
    const toggle = row.locator("button.inline");
    check(await toggle.getAttribute("aria-expanded") === "false" && (await row.locator("th").innerText()).includes("…"),
          `"${result.base_parameters[long].name.slice(0, 30)}…" shows its first terms`);
    await toggle.focus();
    await page.keyboard.press("Enter");
    const full = (await row.locator("th .expr:not([hidden])").innerText()).replace(/\s+/g, " ").trim();
    check(await toggle.getAttribute("aria-expanded") === "true" && full === result.base_parameters[long].name, "... and the whole name on Enter");
  }
  // Filter by name.
  await page.fill("#base-filter", "m7");
  const wanted = result.base_parameters.filter((p) => p.name.toLowerCase().includes("m7")).length;
  check(await page.locator("#base-table tbody tr:not([hidden])").count() === wanted && wanted > 0 &&
        (await page.textContent("#base-count")).includes(`Showing ${wanted} of ${result.base_parameters.length}`),
        `the name filter "m7" leaves the ${wanted} rows that name it`);
  await page.fill("#base-filter", "");
  await page.selectOption("#base-quality", "uncertain");
  const uncertain = result.base_parameters.filter((p) => p.relative_std_error > 0.1 && !(result.unexcited || []).includes(p.name)).length;
  check(await page.locator("#base-table tbody tr:not([hidden])").count() === uncertain, `"σ over 10 %" shows the ${uncertain} uncertain ones`);
  await page.selectOption("#base-quality", "all");
  // Sort by relative σ with the keyboard: ascending, then descending.
  const relativeSort = page.locator('#base-table button.sort[data-key="relative"]');
  await relativeSort.focus();
  await page.keyboard.press("Enter");
  const order = () => page.$$eval("#base-table tbody tr", (trs) => trs.map((tr) => tr.dataset.relative).filter((v) => v !== "").map(Number));
  const ascending = await order();
  check(ascending.every((v, i) => i === 0 || ascending[i - 1] <= v), "Enter on \"Relative σ\" sorts ascending");
  await page.keyboard.press("Enter");
  const descending = await order();
  check(descending.every((v, i) => i === 0 || descending[i - 1] >= v) &&
        await page.getAttribute('#base-table th:has(button[data-key="relative"])', "aria-sort") === "descending", "... and again descending (aria-sort says so)");

  // ---- friction, consistency, identifiability -------------------------------------------------
  const friction = await page.$$eval("#friction-table tbody tr", (trs) => trs.map((tr) => ({
    joint: tr.dataset.joint, values: Object.fromEntries([...tr.querySelectorAll("td[data-key]")].map((td) => [td.dataset.key, Number(td.dataset.value)])) })));
  check(friction.length === JOINTS && friction.every((row, j) => row.joint === robot.joints[j].name &&
        row.values.fv === result.friction[j].fv && row.values.fc === result.friction[j].fc),
        "friction table: fv and fc of the 7 joints, by joint name, as the result");
  const verdict = await page.getAttribute("#consistency-verdict", "data-consistent");
  if (result.consistency) {
    check(verdict === String(result.consistency.consistent), `the consistency verdict is the result's (${verdict})`);
  } else {
    check(verdict === "unknown" && (await page.textContent("#consistency-verdict")).includes("Not assessed"),
          "no consistency in the result: the page says \"not assessed\"");
  }
  check(close(shown(await page.textContent("#condition-number")), result.condition_number, 1e-3), "the condition number is the result's");
  check((await page.textContent("#unidentifiable summary")).startsWith(`${result.unidentifiable.length} standard parameters`),
        `${result.unidentifiable.length} standard parameters that never enter the torque, listed`);
  // Those the physical fit moved (to make their links real bodies) are marked with both values, so the page
  // and the written URDF agree; the rest are the URDF's.
  const movedNames = result.unidentifiable.filter((name) => Math.abs(result.point[name] - result.prior[name]) > 1e-9 * Math.max(1, Math.abs(result.prior[name])));
  check(await page.locator("#unidentifiable li[data-moved=true]").count() === movedNames.length,
        `the ${movedNames.length} moved by the physical fit are marked, with the URDF's value and the point's`);

  // ---- fit: one chart per joint ---------------------------------------------------------------
  const maxPoints = Number(await page.getAttribute("#robot-fit [data-max-points]", "data-max-points"));
  const fit = await json(`${url}/v1/jobs/${jobId}/fit?max_points=${maxPoints}`);
  check(await page.locator("#robot-fit .chart").count() === JOINTS, "7 fit charts, one per joint");
  for (const joint of fit.joints) {
    const box = `#chart-robot-fit-${joint.joint}`;
    check(Number(await page.getAttribute(box, "data-points")) === fit.t.length && await page.getAttribute(box, "data-series") === "3" &&
          await page.getAttribute(box, "data-joint-name") === joint.name,
          `fit chart of ${joint.name}: ${fit.t.length} points (the API's at max_points=${maxPoints}), measured, model, residual`);
  }
  console.log(`      (the 7 fit charts drew in ${await page.getAttribute("#robot-fit .joint-charts", "data-draw-ms")} ms; ` +
              `the 7 validation charts in ${await page.getAttribute("#validation .joint-charts", "data-draw-ms")} ms)`);
  await page.check("#robot-fit input[value=residual]");
  await page.check("#robot-fit input[value=torque]");

  // ---- validation -----------------------------------------------------------------------------
  const validation = await json(`${url}/v1/jobs/${jobId}/validation?max_points=${maxPoints}`);
  const errors = await page.$$eval("#validation-table tbody tr", (trs) => trs.map((tr) => ({
    joint: tr.dataset.joint, estimate: Number(tr.dataset.estimateError), prior: Number(tr.dataset.priorError),
    shown: [...tr.querySelectorAll("td.number")].map((td) => td.textContent) })));
  check(errors.length === JOINTS && errors.every((row, j) => row.joint === validation.joints[j].name &&
        row.estimate === validation.joints[j].relative_error && row.prior === validation.prior.relative_error[j]),
        "validation table: each joint's error, the estimate's beside the URDF values', equal to the API's");
  check(errors.every((row, j) => close(shown(row.shown[0]) / 100, validation.joints[j].relative_error, 6e-3) &&
        close(shown(row.shown[1]) / 100, validation.prior.relative_error[j], 6e-3)), "... shown in % to 3 significant digits");
  check(Number(await page.getAttribute("#validation-table tfoot tr", "data-estimate-error")) === validation.overall_relative_error,
        "... and the overall error");
  const rms = await page.$$eval("#validation-table tbody tr", (trs) => trs.map((tr) => ({
    estimate: Number(tr.dataset.estimateRms), prior: Number(tr.dataset.priorRms), text: tr.querySelector("td.number").textContent })));
  check(rms.every((row, j) => row.estimate === result.validation.rms_error[j] && row.prior === result.validation.prior.rms_error[j] &&
        close(parseFloat(row.text.split("(")[1]), result.validation.rms_error[j], 6e-3) && row.text.includes("N·m")),
        `... each beside its RMS in N·m, the result's (${rms[0].text})`);
  check((await page.textContent("#validation")).includes("judged under a zero-phase 4th-order Butterworth low-pass at 5 Hz"),
        "... and the low-pass the figures were judged under");
  for (const joint of validation.joints) {
    check(Number(await page.getAttribute(`#chart-validation-${joint.joint}`, "data-points")) === validation.t.length,
          `validation chart of ${joint.name}: ${validation.t.length} points`);
  }
  check((await page.textContent("#validation-verdict")).length > 20, "the validation verdict is in words");

  // ---- friction curves: what the rigid body leaves against q̇, with the fitted law ---------------
  check(fit.friction && JSON.stringify(fit.friction.terms) === JSON.stringify(["viscous", "coulomb"]) &&
        fit.friction.joints.length === JOINTS, "the fit carries the friction view of the 7 joints: viscous and Coulomb");
  check(await page.locator("#friction-curves .chart").count() === JOINTS, "7 friction charts, one per joint");
  let curvesDrawn = true, lawIsResult = true, worstLaw = 0, explained = 0, left = 0;
  for (const [j, joint] of fit.friction.joints.entries()) {
    const box = `#chart-friction-${joint.joint}`;
    curvesDrawn &&= Number(await page.getAttribute(box, "data-points")) === joint.qd.filter((v) => v !== null).length &&
                    joint.qd.length === fit.t.length && await page.getAttribute(box, "data-series") === "2" &&
                    await page.getAttribute(box, "data-joint-name") === robot.joints[j].name;
    lawIsResult &&= joint.law.fv === result.friction[j].fv && joint.law.fc === result.friction[j].fc &&
                    Number(await page.getAttribute(box, "data-fv")) === result.friction[j].fv &&
                    Number(await page.getAttribute(box, "data-fc")) === result.friction[j].fc &&
                    (await page.textContent(`${box} .u-title`)).includes(`fv ${Number(result.friction[j].fv.toPrecision(3))}, fc `);
    // The points less the fit's residual are the model's friction torque through the low-pass (the measurement
    // cancels): on the law wherever q̇ is well away from its sign changes.
    const peak = Math.max(...joint.qd.map(Math.abs));
    const law = (v) => joint.law.fv * v + joint.law.fc * Math.sign(v);
    joint.qd.forEach((v, i) => {
      const implied = joint.torque[i] - (fit.joints[j].measured[i] - fit.joints[j].model[i]);
      if (Math.abs(v) >= 0.8 * peak) worstLaw = Math.max(worstLaw, Math.abs(implied - law(v)) / Math.max(Math.abs(law(v)), 1e-3));
      explained += joint.torque[i] ** 2;
      left += (joint.torque[i] - law(v)) ** 2;
    });
  }
  check(curvesDrawn, `each draws the API's ${fit.t.length} (q̇, τ − rigid body) points and the law, by joint name`);
  check(lawIsResult, "... with the law of the result's friction (fv and fc of each joint, in the chart's title)");
  check(worstLaw < 0.02, `the points are the measurement less the model without its friction: the fitted law where |q̇| ≥ 80 % of its peak (worst ${(100 * worstLaw).toFixed(2)} %)`);
  console.log(`      (the friction law explains ${(100 * (1 - left / explained)).toFixed(1)} % of the square of what the rigid body leaves)`);
  await page.locator("#friction-curves").screenshot({ path: shot("robot-job-friction-curves.png") });

  // ---- the run as measured ----------------------------------------------------------------------
  const dataPoints = Number(await page.getAttribute("#robot-data [data-max-points]", "data-max-points"));
  const measuredData = await json(`${url}/v1/datasets/${measured.id}/data?max_points=${dataPoints}`);
  const [header, firstLine] = readFileSync(path.join(workdir, "run1.csv"), "utf8").split("\n");
  const firstRow = Object.fromEntries(header.split(",").map((name, k) => [name.trim(), Number(firstLine.split(",")[k])]));
  check(measuredData.q.length === JOINTS && measuredData.q.every((q, j) => close(q[0], firstRow[`q${j + 1}`], 1e-12)) &&
        measuredData.tau.every((tau, j) => close(tau[0], firstRow[`tau${j + 1}`], 1e-12)), "the dataset's data are the uploaded run's (first row)");
  for (const chart of ["angles", "torques"]) {
    const box = `#chart-robot-${chart}`;
    check(Number(await page.getAttribute(box, "data-points")) === measuredData.t.length && await page.getAttribute(box, "data-series") === String(JOINTS) &&
          (await page.textContent(`${box} .u-legend`)).includes(robot.joints[JOINTS - 1].name),
          `measured ${chart}: one chart, ${measuredData.t.length} points (the API's at max_points=${dataPoints}), 7 joints by name`);
  }
  await page.locator("#robot-data").screenshot({ path: shot("robot-job-measured-data.png") });

  // ---- charts that keep their axes ----------------------------------------------------------------
  // Zoom: a drag across one fit chart zooms the time axis of all seven (one time axis); y fits the window.
  const fitBoxes = fit.joints.map((joint) => `#chart-robot-fit-${joint.joint}`);
  const xRanges = () => Promise.all(fitBoxes.map((box) => axisRange(page, box, "x")));
  const [fullX] = await xRanges();
  await dragAcross(page, fitBoxes[0], 0.25, 0.5);
  const zoomed = await xRanges();
  const span = (range) => range[1] - range[0];
  // Each chart turns the stretch dragged into times with its own width: the same to rounding.
  const sameRange = (a, b) => a.every((value, k) => Math.abs(value - b[k]) <= 1e-9 * span(fullX));
  check(zoomed.every((range) => sameRange(range, zoomed[0])) && span(zoomed[0]) < 0.4 * span(fullX) &&
        zoomed[0][0] > fullX[0], `a drag across one fit chart zooms all 7 to the same stretch (t ${zoomed[0].map((v) => v.toFixed(2)).join("…")} s)`);
  await page.locator("#robot-fit").screenshot({ path: shot("robot-job-fit-zoomed.png") });
  const torqueY = await axisRange(page, fitBoxes[1], "y");
  await page.check("#robot-fit input[value=residual]");
  const residualY = await axisRange(page, fitBoxes[1], "y");
  check(JSON.stringify(await xRanges()) === JSON.stringify(zoomed) && span(residualY) < 0.2 * span(torqueY),
        `the plot switch keeps the zoom; y fits the residual (${fit.joints[1].name}: ±${(span(residualY) / 2).toPrecision(2)} N·m against ±${(span(torqueY) / 2).toPrecision(2)})`);
  await page.check("#robot-fit input[value=torque]");
  const width = () => page.$eval(fitBoxes[0], (box) => box.querySelector(".uplot").getBoundingClientRect().width);
  const wide = await width();
  await page.setViewportSize({ width: 1000, height: 800 });
  await page.waitForFunction(([box, before]) => document.querySelector(box).querySelector(".uplot").getBoundingClientRect().width !== before,
                             [fitBoxes[0], wide]);
  check(JSON.stringify(await xRanges()) === JSON.stringify(zoomed), "a resize keeps the zoom");
  await page.setViewportSize({ width: 1280, height: 800 });
  await page.locator(`${fitBoxes[3]} .u-over`).dblclick();
  check(JSON.stringify(await xRanges()) === JSON.stringify(fit.joints.map(() => fullX)), "a double-click on any of them shows the whole run again in all 7");
  // The legend: hiding a joint leaves the axes where they are (the other curves do not jump).
  const torques = "#chart-robot-torques";
  const legendEntry = (k) => page.locator(`${torques} .u-legend .u-series:nth-child(${k + 2}) th`);  // k: 0-based joint
  const peak = (values) => Math.max(...values.filter((v) => v !== null).map(Math.abs));
  const largest = measuredData.tau.reduce((best, tau, j) => (peak(tau) > peak(measuredData.tau[best]) ? j : best), 0);
  const allY = await axisRange(page, torques, "y");
  const plotLeft = () => page.$eval(`${torques} .u-over`, (over) => over.style.left);
  const plotLeftBefore = await plotLeft();
  await legendEntry(largest).click();
  check(await page.locator(`${torques} .u-legend .u-series:nth-child(${largest + 2}).u-off`).count() === 1 &&
        JSON.stringify(await axisRange(page, torques, "y")) === JSON.stringify(allY),
        `hiding ${robot.joints[largest].name} (the largest torque) from the legend keeps the y axis (${allY.join(" … ")} N·m)`);
  await page.locator(`${torques} .u-over`).dblclick();
  const restY = await axisRange(page, torques, "y");
  check(span(restY) < span(allY), `... a double-click fits it to the joints left (${restY.join(" … ")} N·m)`);
  await legendEntry(largest).click();
  const backY = await axisRange(page, torques, "y");
  const tauLargest = measuredData.tau[largest].filter((v) => v !== null);
  check(backY[0] <= Math.min(...tauLargest) && backY[1] >= Math.max(...tauLargest) && backY[0] <= restY[0] && backY[1] >= restY[1],
        `... shown again, y widens to hold it (${backY.join(" … ")} N·m), never narrows`);
  for (let j = 0; j < JOINTS; j += 1) await legendEntry(j).click();
  check(await page.locator(`${torques} .u-legend .u-series.u-off`).count() === JOINTS &&
        JSON.stringify(await axisRange(page, torques, "y")) === JSON.stringify(backY) && await plotLeft() === plotLeftBefore,
        "every joint hidden: the y axis stays, with its ticks and label, and the plot where it was");
  await page.locator(torques).screenshot({ path: shot("robot-job-torques-all-hidden.png") });
  for (let j = 0; j < JOINTS; j += 1) await legendEntry(j).click();

  // ---- the base parameters' correlation ------------------------------------------------------------
  const base = result.base_parameters.length;
  check(Number(await page.getAttribute("#correlation-map", "data-size")) === base &&
        await page.locator("#correlation-map tbody tr").count() === base &&
        await page.locator("#correlation-map tbody tr:first-child td").count() === base, `correlation map: ${base} × ${base} cells`);
  let cellsRight = true;
  for (const [i, j] of [[0, 0], [0, base - 1], [Math.floor(base / 2), 3], [base - 1, base - 2]]) {
    const title = await page.getAttribute(`#correlation-map tbody tr:nth-child(${i + 1}) td:nth-child(${j + 2})`, "title");
    const value = result.correlation[i][j];
    cellsRight &&= title === `corr(#${i + 1} ${result.base_parameters[i].name}, #${j + 1} ${result.base_parameters[j].name}) = ${value.toFixed(2)}`;
  }
  check(cellsRight, "... each cell's title names its pair and gives the result's correlation");
  const offDiagonal = result.correlation.flatMap((row, i) => row.filter((_, j) => j > i)).sort((a, b) => Math.abs(b) - Math.abs(a));
  const listed = await page.$$eval("#correlation-strong li[data-value]", (items) => items.map((li) => Number(li.dataset.value)));
  check(listed.length === 10 && listed.every((value, k) => Math.abs(value) === Math.abs(offDiagonal[k])) &&
        Number(await page.getAttribute("#correlation-strong-count", "data-count")) === offDiagonal.filter((v) => Math.abs(v) >= 0.9).length,
        `the 10 most correlated pairs listed by name, strongest first (${listed[0]?.toFixed(3)}), and how many reach ±0.9`);
  await page.locator("#correlation").screenshot({ path: shot("robot-job-correlation.png") });

  // ---- the identified URDF --------------------------------------------------------------------
  check(await page.getAttribute("#urdf-download", "href") === `/v1/jobs/${jobId}/urdf`, "the download link is /v1/jobs/{id}/urdf");
  const [download] = await Promise.all([page.waitForEvent("download"), page.click("#urdf-download")]);
  const file = await download.path();
  check(download.suggestedFilename().endsWith("-identified.urdf") && readFileSync(file, "utf8").includes("<robot"),
        `it downloads ${download.suggestedFilename()}, a URDF`);
  const firstLink = result.links[0];
  check(await page.locator("#links-table tbody tr").count() === JOINTS &&
        Number(await page.getAttribute(`#links-table tr[data-link="${firstLink.link}"]`, "data-mass")) === firstLink.mass &&
        await page.getAttribute(`#links-table tr[data-link="${firstLink.link}"]`, "data-determined") ===
          (firstLink.determined.inertia_about_com ? "all" : firstLink.determined.centre_of_mass ? "mass, centre of mass"
            : firstLink.determined.mass ? "mass" : "only in combinations"),
        `the links table: 7 links, mass, centre of mass, inertia about it and what the data determine (${firstLink.link}: ${firstLink.mass} kg)`);
  await page.locator("#links").screenshot({ path: shot("robot-job-links.png") });
  await page.screenshot({ path: shot("robot-job-1280x800.png"), fullPage: true });

  // ---- keyboard --------------------------------------------------------------------------------
  await page.focus("a.skip");  // Tab from the top of the page
  const reached = new Set();
  for (let presses = 0; presses < 250 && reached.size < 6; presses += 1) {
    await page.keyboard.press("Tab");
    const focus = await page.evaluate(() => {
      const element = document.activeElement;
      const outline = getComputedStyle(element).outlineStyle;
      return { id: element.id || element.dataset?.key || element.getAttribute("value") || "", outline };
    });
    if (["robot-link", "urdf-download", "base-filter", "base-quality", "relative", "torque"].includes(focus.id) && focus.outline !== "none") {
      reached.add(focus.id);
    }
  }
  check(reached.size === 6, `Tab reaches the robot link, the download, the filter, the sort buttons and the plot switch, with a visible focus (${[...reached]})`);

  // ---- a narrow screen --------------------------------------------------------------------------
  await page.setViewportSize({ width: 390, height: 844 });
  await page.waitForTimeout(300);  // let the charts follow the resize (not a timing assertion)
  const narrow = await overflow(page);
  check(narrow <= 1, `robot job page: no sideways scrolling at 390 px (overflow ${narrow} px; tables scroll in place)`);
  await page.screenshot({ path: shot("robot-job-390.png"), fullPage: true });
  await page.locator("#correlation").screenshot({ path: shot("robot-job-correlation-390.png") });
  await page.locator("#friction-curves").screenshot({ path: shot("robot-job-friction-curves-390.png") });
  await page.setViewportSize({ width: 1280, height: 800 });

  // ---- an inconsistent estimate, a constrained fit, an unexcited parameter ------------------------
  // The noisy run above gives none of these for sure; the page renders them from the job's JSON,
  // so give it a result that has them all.
  const bad = new Set([2, 4]);
  const withChecks = { ...job, result: { ...result,
    unexcited: [result.base_parameters[0].name],
    consistency: { consistent: false, findings: ["2 of 7 links are not physically consistent"],
                   links: robot.joints.map((joint, k) => ({ link: joint.link, consistent: !bad.has(k),
                     findings: bad.has(k) ? ["pseudo-inertia not positive definite (smallest eigenvalue -0.01)"] : [] })) },
    physical: { cost_increase: 0.0123, message: "The consistent estimate was found in 12 iterations." } } };
  await page.route(`**/v1/jobs/${jobId}`, (route) => route.fulfill({ json: withChecks }));
  await page.reload();
  await page.waitForSelector("body[data-ready=true] #consistency-links");
  check(await page.getAttribute("#consistency-verdict", "data-consistent") === "false" &&
        (await page.textContent("#consistency-verdict")).includes("2 of 7 links"), "consistent: false — \"Not physically consistent: 2 of 7 links …\"");
  check(await page.locator("#consistency-links tbody tr").count() === JOINTS &&
        await page.locator('#consistency-links tr[data-consistent="false"]').count() === 2 &&
        (await page.textContent(`#consistency-links tr[data-link="${robot.joints[2].link}"]`)).includes("pseudo-inertia"),
        "... each link's verdict and findings, by link name");
  check((await page.textContent("#consistency-glance")).includes(`${robot.joints[2].link}, ${robot.joints[4].link}`), "... named at a glance");
  check((await page.textContent("#physical-summary")).includes("1.23 %") && (await page.textContent("#physical-summary")).includes("12 iterations"),
        "physical: the cost increase in % and the message");
  check(await page.getAttribute('#base-table tr[data-index="1"]', "data-quality") === "unexcited" &&
        (await page.textContent('#base-table tr[data-index="1"]')).includes("barely seen"), "an unexcited base parameter is marked");
  await page.locator("#consistency").screenshot({ path: shot("robot-job-consistency.png") });
  // No URDF for links that are no bodies: said at a glance, with the same request again, physically consistent.
  check(await page.locator("#urdf-download").count() === 0 &&
        (await page.textContent("#urdf-unavailable")).includes(`${robot.joints[2].link}, ${robot.joints[4].link} of this estimate are not`),
        "an inconsistent estimate: no download, the links named instead");
  await page.locator("#glance").screenshot({ path: shot("robot-job-no-urdf.png") });
  await page.click("#identify-physical");
  await page.waitForURL((address) => /\/jobs\/job_[0-9a-f]+$/.test(address.pathname) && !address.pathname.endsWith(jobId), { timeout: 30000 });
  const again = await json(`${url}/v1/jobs/${page.url().split("/").pop()}`);
  check(again.request.physical === true && JSON.stringify(again.request.dataset_ids) === JSON.stringify(job.request.dataset_ids) &&
        JSON.stringify(again.request.validation_dataset_ids) === JSON.stringify(job.request.validation_dataset_ids) &&
        again.request.robot_id === robotId, "... its button asks for the same identification with physical: true");
  await page.unroute(`**/v1/jobs/${jobId}`);
  await page.goto(`${url}/jobs/${jobId}`);  // back where the rest of the test expects to be
  await page.waitForSelector("body[data-ready=true] #urdf-download");

  // ---- the robots list, and the robot's page from the job --------------------------------------
  await page.click('header nav a[href="/robots"]');
  await page.waitForSelector(`#robots tr[data-robot-id="${robotId}"]`);
  const row = `#robots tr[data-robot-id="${robotId}"]`;
  check(await page.getAttribute(row, "data-joints") === String(JOINTS) &&
        await page.getAttribute(row, "data-base-parameters") === String(robot.base_parameters.count),
        `the robots list shows ${robot.name}: 7 joints, ${robot.base_parameters.count} base parameters`);
  await page.focus(`${row} summary`);
  await page.keyboard.press("Enter");
  check(await page.locator(`${row} details table tbody tr`).count() === JOINTS, "... its joints (types, limits) open with Enter");
  await page.screenshot({ path: shot("robots-1280x800.png"), fullPage: true });
  await page.setViewportSize({ width: 390, height: 844 });
  const listNarrow = await overflow(page);
  check(listNarrow <= 1, `robots list: no sideways scrolling at 390 px (overflow ${listNarrow} px)`);
  await page.setViewportSize({ width: 1280, height: 800 });

  await page.goBack();
  await page.waitForURL(new RegExp(`/jobs/${jobId}$`));
  await page.waitForSelector("body[data-ready=true] #robot-link");
  check(true, "Back returns to the job page");
  await page.click("#robot-link");
  await page.waitForURL(new RegExp(`/robots/${robotId}$`));
  await page.waitForSelector("body[data-ready=true] #robot-jobs-table");
  check(await page.locator(`#robot-jobs-table tr[data-job-id="${jobId}"]`).count() === 1, "the robot's page lists the identification");
  await page.screenshot({ path: shot("robot-1280x800.png"), fullPage: true });

  // ---- an excitation, designed from the robot's page --------------------------------------------
  // A lab's run: a budget of evaluations (the same result on any machine), a start pose to ramp from and
  // back, a torque limit below the URDF's efforts and a jerk limit.
  await page.fill("#e-duration", "10");
  await page.fill("#e-max-evaluations", "300");
  await page.fill("#e-start-pose", "0, 0, 0, -1.5, 0, 1.5, 0");
  await page.fill("#e-max-torque", "60");
  await page.fill("#e-max-jerk", "40");
  await page.focus("#excitation-submit");
  await page.keyboard.press("Enter");
  await page.waitForURL(/\/jobs\/job_[0-9a-f]+$/, { timeout: 30000 });
  const excitationId = page.url().split("/").pop();
  await page.waitForSelector("body[data-ready=true]", { timeout: 240000 });
  const excitation = await json(`${url}/v1/jobs/${excitationId}`);
  check(excitation.kind === "excitation" && excitation.state === "succeeded" && excitation.request.duration === 10,
        `excitation ${excitationId} succeeded (10 s asked from the form)`);
  check(Number(await page.getAttribute("#excitation-condition", "data-value")) === excitation.result.condition_number,
        `its page gives the condition number, ${excitation.result.condition_number}`);
  const excitationPoints = Number(await page.getAttribute("#excitation-angles [data-max-points]", "data-max-points"));
  const trajectory = await json(`${url}/v1/datasets/${excitation.result.dataset_id}/data?max_points=${excitationPoints}`);
  check(await page.locator("#excitation-angles .chart").count() === JOINTS, "7 angle charts, one per joint");
  let anglesRight = true;
  for (let k = 1; k <= JOINTS; k += 1) {
    anglesRight &&= Number(await page.getAttribute(`#chart-excitation-q-${k}`, "data-points")) === trajectory.t.length &&
                    await page.getAttribute(`#chart-excitation-q-${k}`, "data-series") === "3";
  }
  check(anglesRight, `each draws the dataset's ${trajectory.t.length} points (the API's) with its lower and upper limits`);
  const design = excitation.result.coefficients;
  check(excitation.request.max_evaluations === 300 && design.evaluations === 300 && JSON.stringify(excitation.request.start_pose) === "[0,0,0,-1.5,0,1.5,0]" &&
        excitation.request.max_torque === 60 && excitation.request.max_jerk === 40,
        "the form sent the evaluation budget, the start pose and the torque and jerk limits");
  check(excitation.result.ramp_duration > 0 && trajectory.q[3][0] === -1.5 && trajectory.q[5][trajectory.t.length - 1] === 1.5 &&
        (await page.textContent("#excitation-ramp")).includes("ramps of"),
        `the run starts and ends at the start pose, ramps of ${excitation.result.ramp_duration} s, said on the page`);
  check(design.limits.torque[1] === 60 && design.limits.torque[6] === 12 && design.peaks.torque.every((peak, j) => peak <= design.limits.torque[j]) &&
        design.peaks.jerk.every((peak) => peak <= 40),
        "torque limits min(60, the URDF's effort) and the jerk limit held over the period");
  check(await page.locator("#excitation-usage tbody tr").count() === JOINTS &&
        Number(await page.getAttribute("#excitation-usage tbody tr:nth-child(2) td[data-kind=torque]", "data-usage")) === design.usage.torque[1],
        "the limits table gives each joint's share of its limits");
  let ratesRight = true;
  for (const [key, section, limit] of [["qd", "excitation-velocities", "velocity"], ["qdd", "excitation-accelerations", "acceleration"],
                                       ["tau", "excitation-torques", "torque"]]) {
    ratesRight &&= await page.locator(`#${section} .chart`).count() === JOINTS &&
                   await page.getAttribute(`#chart-excitation-${key}-2`, "data-series") === (typeof design.limits[limit][1] === "number" ? "3" : "1");
  }
  const torquePoints = excitation.result.torque.t.length;
  check(ratesRight && Number(await page.getAttribute("#chart-excitation-tau-1", "data-points")) === torquePoints &&
        excitation.result.torque.tau.every((tau, j) => tau.every((value) => Math.abs(value) <= design.limits.torque[j] + 1e-9)),
        `velocity, acceleration and torque charts per joint with ± their limits (torque: ${torquePoints} points, all within)`);
  await page.screenshot({ path: shot("excitation-job-1280x800.png"), fullPage: true });

  // The job list names the robot of each robot job; the home page leads to the robots.
  await page.click("a.brand");
  await page.waitForSelector(`#jobs tr[data-job-id="${jobId}"]`);
  const robotCell = page.locator(`#jobs tr[data-job-id="${jobId}"] a[href="/robots/${robotId}"]`);
  check(await robotCell.count() === 1 && (await robotCell.textContent()) === robot.name && await robotCell.getAttribute("title") === robotId,
        `the job list links the robot by its name, "${robot.name}" (its id on hover)`);
  check(await page.getAttribute("#robots-card-link", "href") === "/robots" &&
        (await page.textContent("#robots-card-link")).includes("upload a URDF"), "the home page has a way to the robots: \"Your own arm: upload a URDF\"");
  await page.locator("#robots-card").screenshot({ path: shot("home-robots-card.png") });
  await page.click("#robots-card-link");
  await page.waitForSelector(`body[data-ready=true] #robots tr[data-robot-id="${robotId}"]`);
  check(true, "... which opens the robots list");
  await page.goBack();
  await page.waitForSelector(`#jobs tr[data-job-id="${jobId}"]`);
  await page.selectOption("#filter-kind", "robot_identification");
  await page.waitForFunction((id) => {
    const rows = [...document.querySelectorAll("#jobs tbody tr")];
    return rows.length > 0 && rows.every((row) => row.querySelector("td:nth-child(2)")?.textContent === "robot_identification") &&
           rows.some((row) => row.dataset.jobId === id);
  }, jobId, { timeout: 10000 });
  check(true, "the job list's kind filter finds the robot identification under robot_identification");

  check(consoleErrors.length === 0, `no console errors${consoleErrors.length ? ": " + consoleErrors.join(" | ") : ""}`);

  // A URDF the server refuses: the form says why and stays. (After the console check: the
  // browser logs the 422 it meets as a console error.)
  await page.goto(`${url}/robots`);
  await page.waitForSelector("body[data-ready=true] #robot-upload");
  await page.setInputFiles("#u-file", { name: "broken.urdf", mimeType: "application/xml", buffer: Buffer.from("<robot name='x'><link") });
  await page.click("#robot-upload-submit");
  await page.waitForSelector('#robot-upload .form-status[role="alert"]');
  check(page.url().endsWith("/robots") && (await page.textContent("#robot-upload .form-status")).length > 10,
        `a broken URDF: the form shows the server's reason ("${(await page.textContent("#robot-upload .form-status")).slice(0, 60)}…")`);

  // A CSV the server refuses, beside a good one: the identify form names the file and the reason, and stays.
  await page.goto(`${url}/robots/${robotId}`);
  await page.waitForSelector("body[data-ready=true] #identify-form");
  const datasetsBefore = (await json(`${url}/v1/datasets?page_size=100`)).items.length;
  await page.setInputFiles("#i-files", [{ name: "notes.csv", mimeType: "text/csv", buffer: Buffer.from("time,position\n0,1\n0.1,2\n") },
                                        { name: "run2-again.csv", mimeType: "text/csv", buffer: readFileSync(path.join(workdir, "run2.csv")) }]);
  check(await page.inputValue('#i-runs tr[data-file="notes.csv"] select') === "train" &&
        await page.inputValue('#i-runs tr[data-file="run2-again.csv"] select') === "validation" &&
        (await page.$$eval("#i-runs tr[data-dataset-id] select", (selects) => selects.map((select) => select.value))).every((v) => v === "unused"),
        "two files added: the first a training run, the second a validation run, the stored runs set to \"not used\"");
  await page.click("#identify-submit");
  await page.waitForSelector('#identify-form .form-status[role="alert"]');
  await page.waitForFunction(() => !document.querySelector("#identify-submit").disabled);
  const refusal = await page.textContent("#identify-form .form-status");
  const why = await page.textContent('#i-runs tr[data-file="notes.csv"] .run-status');
  check(page.url().endsWith(`/robots/${robotId}`) && refusal.includes("notes.csv") && !refusal.includes("run2-again.csv") &&
        await page.getAttribute('#i-runs tr[data-file="notes.csv"]', "data-refused") === "true" && why.startsWith("refused: t: missing column t") &&
        await page.getAttribute('#i-runs tr[data-file="run2-again.csv"]', "data-dataset-id") !== null,
        `a refused CSV: the form names the file ("${refusal}") and its row the server's reason ("${why.slice(0, 60)}…"); ` +
        "the good one is stored, nothing identified");
  check((await json(`${url}/v1/datasets?page_size=100`)).items.length === datasetsBefore + 1, "... exactly one dataset was added");
  await page.locator("#identify-form").screenshot({ path: shot("identify-form-refused.png") });

} catch (error) {
  check(false, `unexpected: ${error.stack || error}`);
} finally {
  await browser.close();
  check(await stopServer(server) === 0, "the server exits 0 on SIGTERM");
  rmSync(workdir, { recursive: true, force: true });
}
console.log(failed() ? `${failed()} check(s) failed; screenshots in ${artifacts}` : `all checks passed; screenshots in ${artifacts}`);
process.exit(failed() ? 1 : 0);

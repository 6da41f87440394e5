// dashboard_test.mjs — the web dashboard end to end in headless Chromium (Debian's chromium,
// driven by playwright-core from web/node_modules): start `manipid serve --port 0` on a fresh
// SQLite file, open /, reach the paper's form and submit it with the keyboard alone, follow
// the job page until it has drawn everything, then check the charts hold the number of points
// the API says they should, the result table the job's estimates, that the page fits a narrow
// screen, and that the console stayed clean. Screenshots go to ARTIFACT_DIR.
//
//   node tests/dashboard/dashboard_test.mjs path/to/manipid ARTIFACT_DIR
//
// Exit 0: pass; 1: a check failed; 77: skipped (no chromium, or playwright-core not installed).
import { mkdirSync, mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import path from "node:path";
import { axisRange, check, chromiumOrSkip, dragAcross, failed, json, launch, newPage, startServer, stopServer } from "./support.mjs";

const [binary, artifacts = path.join(tmpdir(), "manipid-dashboard-artifacts")] = process.argv.slice(2);
if (!binary) { console.error("usage: dashboard_test.mjs path/to/manipid [ARTIFACT_DIR]"); process.exit(2); }
const chromium = chromiumOrSkip();

const workdir = mkdtempSync(path.join(tmpdir(), "manipid-dashboard-"));
mkdirSync(artifacts, { recursive: true });
const { server, url } = await startServer(binary, path.join(workdir, "jobs.db"));
const browser = await launch(chromium);
const consoleErrors = [];
try {
  const page = await newPage(browser, consoleErrors);

  await page.goto(`${url}/`);
  await page.waitForSelector("#paper-form");
  check(await page.inputValue("#f-initial-m2") === "25.1", "the form starts from the paper's initial values (m2 = 25.1)");
  check(await page.inputValue("#f-duration") === "9.7", "... and its 9.7 s experiment");

  // Keyboard only: Tab until the submit button has focus, then Enter.
  let reached = false;
  for (let presses = 0; presses < 80 && !reached; presses += 1) {
    await page.keyboard.press("Tab");
    reached = await page.evaluate(() => document.activeElement?.id === "paper-submit");
  }
  check(reached, "the submit button is reachable with Tab");
  await page.keyboard.press("Enter");
  await page.waitForURL(/\/jobs\/job_[0-9a-f]+$/, { timeout: 30000 });
  const jobId = page.url().split("/").pop();
  await page.waitForSelector("body[data-ready=true]", { timeout: 240000 });
  check(await page.getAttribute("body", "data-job-state") === "succeeded", `job ${jobId} reached succeeded on its page`);
  check((await page.textContent("#job-state")).trim() === "succeeded", "the state badge says succeeded");

  // What the charts should hold, from the API.
  const job = await json(`${url}/v1/jobs/${jobId}`);
  const overview = await json(`${url}/v1/jobs/${jobId}/history?max_points=2000`);
  const data = await json(`${url}/v1/datasets/${job.dataset_id}/data?max_points=2000`);
  const fit = await json(`${url}/v1/jobs/${jobId}/fit?max_points=2000`);
  const points = (selector) => page.getAttribute(selector, "data-points").then(Number);
  const series = (selector) => page.getAttribute(selector, "data-series").then(Number);
  // Every evaluation is drawn (LM takes ~10 on this case, far below the 2,000 the view thins to).
  check(await points("#chart-cost") === overview.items.length && overview.items.length === overview.total &&
        overview.total >= 5, `cost chart: ${overview.items.length} points of ${overview.total} evaluations`);
  for (const name of ["m1", "m2", "m3", "m4", "l1", "l2", "l3", "l4"]) {
    const selector = `#chart-parameter-${name}`;
    check(await points(selector) === overview.items.length && await series(selector) === 2, `${name} chart: estimate and true value`);
  }
  check(await points("#chart-angles") === data.t.length && data.t.length === 1941, "angle chart: 1941 points (9701 samples, every 5th and the last)");
  check(await series("#chart-angles") === 8, "angle chart: q1..q4 and ref1..ref4");
  check(await series("#chart-torques") === 4, "torque chart: tau1..tau4");
  for (const joint of [1, 2, 3, 4]) check(await points(`#chart-fit-${joint}`) === fit.t.length, `fit chart of joint ${joint}`);
  check(await series("#chart-residual") === 4, "residual chart: four joints");
  check(await page.locator("canvas").count() >= 16, "every chart drew a canvas");

  // The table shows the job's estimates.
  for (const name of ["m2", "m3", "m4", "l2", "l3", "l4"]) {
    const shown = Number(await page.getAttribute(`#result-table tr[data-parameter="${name}"] td[data-estimate]`, "data-estimate"));
    check(shown === job.result.estimates[name], `table: ${name} = ${shown}`);
    check(Math.abs(shown - { m2: 25, m3: 15, m4: 5, l2: 0.8, l3: 0.6, l4: 0.2 }[name]) < 1e-3 * shown, `${name} is within 0.1 % of the truth`);
  }
  check((await page.textContent('#result-table tr[data-parameter="m1"]')).includes("not alone"), "m1 is not given alone");
  check(await page.locator('#result-table tr[data-parameter="m1*l1^2"]').count() === 1, "m1*l1^2 is reported instead");
  check((await page.textContent("#findings")).includes("m1*l1^2"), "the findings say why, in words");
  check(await page.locator("#correlation tbody td").count() === 36, "6 × 6 correlation heat map (m1 and l1 have none)");
  await page.screenshot({ path: path.join(artifacts, "job-1280x800.png"), fullPage: true });

  // The same data uploaded: nothing says which robot made them, so no true values anywhere —
  // unless the request gives them ("truth").
  const csv = await fetch(`${url}/v1/datasets/${job.dataset_id}/data?format=csv`).then((r) => r.text());
  const uploaded = await fetch(`${url}/v1/datasets`, { method: "POST", headers: { "Content-Type": "text/csv" }, body: csv })
    .then((r) => r.json());
  const identifyUploaded = (extra) => fetch(`${url}/v1/identifications`, {
    method: "POST", headers: { "Content-Type": "application/json" },
    body: JSON.stringify({ dataset_id: uploaded.id, half_length: 100, band: 0.2, ...extra }) }).then((r) => r.json());
  for (const [truth, label] of [[undefined, "uploaded data"], [{ m2: 25 }, "uploaded data with truth"]]) {
    const submitted = await identifyUploaded(truth ? { truth } : {});
    await page.goto(`${url}/jobs/${submitted.id}`);
    await page.waitForSelector("body[data-ready=true]", { timeout: 240000 });
    const head = await page.textContent("#result-table thead");
    check(head.includes("True") === Boolean(truth), `${label}: ${truth ? "a" : "no"} True column`);
    check(await series("#chart-parameter-m2") === (truth ? 2 : 1), `${label}: m2 chart ${truth ? "with" : "without"} a true value`);
    if (truth) {
      const row = await page.textContent('#result-table tr[data-parameter="m2"]');
      check(row.includes("25"), "... the given m2 = 25 beside the estimate");
    }
  }
  await page.goto(`${url}/jobs/${jobId}`);  // back to the paper's job for the narrow-screen check
  await page.waitForSelector("body[data-ready=true]", { timeout: 240000 });

  // A narrow screen: nothing wider than the viewport but the scrollable tables.
  await page.setViewportSize({ width: 390, height: 844 });
  await page.waitForTimeout(300);
  const overflow = await page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
  check(overflow <= 1, `no sideways scrolling at 390 px (overflow ${overflow} px)`);
  await page.screenshot({ path: path.join(artifacts, "job-390.png"), fullPage: true });

  // Back to the list: the job is there, by keyboard-followable link.
  await page.setViewportSize({ width: 1280, height: 800 });
  await page.click('a.brand');
  await page.waitForSelector(`#jobs tr[data-job-id="${jobId}"]`);
  check((await page.textContent(`#jobs tr[data-job-id="${jobId}"] .badge`)).trim() === "succeeded", "the job list shows it succeeded");
  await page.screenshot({ path: path.join(artifacts, "jobs-1280x800.png") });

  // Live: a long job's page redraws its charts as evaluations arrive; Cancel (by keyboard) stops it.
  const post = (route, body) => fetch(`${url}${route}`, { method: "POST", headers: { "Content-Type": "application/json" },
                                                          body: JSON.stringify(body) }).then((r) => r.json());
  // Output-error: a closed-loop simulation per evaluation (~1 ms each in release). Nothing
  // about speed is assumed: the job cannot end on its own before Cancel reaches it. Its
  // tolerances are 0 (NLopt's x and f stops never fire); it runs Subplex, which crawls on this
  // problem (still running and improving after 60 s, ~55,000 evaluations, in release), on noisy
  // angles (no exact zero-cost optimum to collapse onto, as BOBYQA and Nelder–Mead do on clean
  // data after 2,200–2,600 evaluations even with zero tolerances); and its budgets, a million
  // evaluations or 120 s, are far beyond the few seconds the page takes to cancel it on any
  // build, release or sanitized.
  const long = await post("/v1/identifications", {
    simulation: { duration: 2.0, noise: { q_sigma: 1e-4 } }, method: "output-error", algorithm: "LN_SBPLX",
    relative_x_tolerance: 0, relative_f_tolerance: 0, max_evaluations: 1000000, max_seconds: 120 });
  await page.goto(`${url}/jobs/${long.id}`);
  await page.waitForSelector("body[data-job-state=running]", { timeout: 60000 });
  await page.waitForSelector("#chart-cost[data-total]", { timeout: 60000 });
  const first = Number(await page.getAttribute("#chart-cost", "data-total"));
  await page.waitForFunction((seen) => Number(document.querySelector("#chart-cost").dataset.total) > seen, first, { timeout: 60000 });
  const later = Number(await page.getAttribute("#chart-cost", "data-total"));
  check(later > first, `the running job's charts follow it live (${first} → ${later} evaluations)`);
  check(await points("#chart-cost") <= 2002, "... drawn from at most about 2000 points");
  // A live chart keeps the reader's zoom through its refreshes; one left alone follows the job.
  await dragAcross(page, "#chart-cost", 0.2, 0.5);
  const zoomedCost = await axisRange(page, "#chart-cost", "x");
  const followed = await axisRange(page, "#chart-parameter-m2", "x");
  const beforeRefresh = Number(await page.getAttribute("#chart-cost", "data-total"));
  await page.waitForFunction((seen) => Number(document.querySelector("#chart-cost").dataset.total) > seen, beforeRefresh, { timeout: 60000 });
  const afterRefresh = await axisRange(page, "#chart-cost", "x");
  check(zoomedCost[1] < followed[1] && JSON.stringify(afterRefresh) === JSON.stringify(zoomedCost),
        `a zoomed live chart keeps its window through a refresh (evaluations ${zoomedCost.map(Math.round).join("…")})`);
  check((await axisRange(page, "#chart-parameter-m2", "x"))[1] > followed[1], "... and an unzoomed one follows the job as it grows");
  await page.focus("#cancel");
  await page.keyboard.press("Enter");
  await page.waitForSelector("body[data-ready=true]", { timeout: 120000 });
  const ended = await page.getAttribute("body", "data-job-state");
  check(ended === "cancelled", `Cancel stops it; the page says cancelled (${ended})`);
  check(await page.locator("#result-table").count() === 1, "a cancelled job shows its best point so far");

  // A simulation's page: its data (Fig. 2).
  const simulation = await post("/v1/simulations", { duration: 1.5 });
  await page.goto(`${url}/jobs/${simulation.id}`);
  await page.waitForSelector("body[data-ready=true]", { timeout: 120000 });
  check(await points("#chart-angles") === 1501 && await series("#chart-torques") === 4, "a simulation's page draws its 1501 samples");

  // A cost that converges to ~1e-27 (output-error on clean data does) on the log axis: uPlot's
  // own log ticks never end below ~1e-25 (RangeError: Invalid array length); the charts draw
  // their own. Drawn off the job page's path, on this page, and left a frame to render.
  const tiny = await page.evaluate(async () => {
    const errors = [];
    const onError = (event) => errors.push(String(event.message || event.error));
    window.addEventListener("error", onError);
    const { lineChart, positive } = await import("/assets/charts.js");
    const box = Object.assign(document.createElement("div"), { id: "chart-tiny-cost" });
    document.querySelector("main").append(box);
    const index = [0, 1, 2, 3, 4, 5];
    const cost = [3e-5, 2e-10, 1e-18, 1e-23, 1.3e-27, 4e-27];
    const chart = lineChart(box, { title: "tiny cost", xLabel: "evaluation", yLabel: "cost (log)", logY: true,
                                   series: [{ label: "cost" }], data: [index, positive(cost)] });
    await new Promise((resolve) => requestAnimationFrame(() => setTimeout(resolve, 50)));
    chart.update([[...index, 6], positive([...cost, 0])]);
    await new Promise((resolve) => requestAnimationFrame(() => setTimeout(resolve, 50)));
    window.removeEventListener("error", onError);
    const points = Number(box.dataset.points);
    box.remove();
    return { points, errors };
  });
  check(tiny.points === 7 && tiny.errors.length === 0,
        `a log-scale cost chart down to 1e-27 draws${tiny.errors.length ? ": " + tiny.errors.join(" | ") : ""}`);

  check(consoleErrors.length === 0, `no console errors${consoleErrors.length ? ": " + consoleErrors.join(" | ") : ""}`);

  // A section that cannot be drawn explains itself; the rest of the page stands. (After the
  // console check: the browser logs the 404 it meets as a console error.)
  const finished = await json(`${url}/v1/jobs/${simulation.id}`);
  await fetch(`${url}/v1/datasets/${finished.dataset_id}`, { method: "DELETE" });
  await page.goto(`${url}/jobs/${simulation.id}`);
  await page.waitForSelector("body[data-ready=true]", { timeout: 60000 });
  check((await page.textContent("main")).includes(`no dataset ${finished.dataset_id}`),
        "a deleted dataset: its section says so, the page still loads");
} catch (error) {
  check(false, `unexpected: ${error.stack || error}`);
} finally {
  await browser.close();
  check(await stopServer(server) === 0, "the server exits 0 on SIGTERM");
  rmSync(workdir, { recursive: true, force: true });
}
console.log(failed() ? `${failed()} check(s) failed; screenshots in ${artifacts}` : `all checks passed; screenshots in ${artifacts}`);
process.exit(failed() ? 1 : 0);

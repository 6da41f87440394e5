// payload_dashboard_test.mjs — a payload identification's page end to end in headless Chromium: make runs of a
// 6-joint arm with the real binary (`manipid excitation`, `manipid torque` with noise; a tool of known mass, centre
// of mass and inertia mounted on the tip link by clients/python/tests/robot_data.py's with_tool), start `manipid
// serve --port 0`, identify the arm by the API, then the tool with a validation run and a run without it; check the
// payload card against the API (the verdict, the values with their standard errors, the undetermined names and
// warnings, the torque errors, the URDF download, the arm's job), the centre of mass drawn on the flange where it
// is (both views, its two-standard-error ellipse), the torque with and without the payload per joint (/fit and
// /validation), the measured run, the page of the run without the tool (no payload: not an error, no point, no
// URDF), the job list's kind filter, keyboard reach, a narrow screen and a clean console. Screenshots go to
// ARTIFACT_DIR.
//
//   node tests/dashboard/payload_dashboard_test.mjs path/to/manipid ARTIFACT_DIR
//
// Exit 0: pass; 1: a check failed; 77: skipped (no chromium, or playwright-core not installed).
import { execFileSync } from "node:child_process";
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import path from "node:path";
import { check, chromiumOrSkip, failed, json, launch, newPage, overflow, root, startServer, stopServer, tabUntil } from "./support.mjs";

const [given, artifacts = path.join(tmpdir(), "manipid-dashboard-artifacts")] = process.argv.slice(2);
const binary = given && path.resolve(given);
if (!binary) { console.error("usage: payload_dashboard_test.mjs path/to/manipid [ARTIFACT_DIR]"); process.exit(2); }
const chromium = chromiumOrSkip();

const URDF = path.join(root, "examples/robots/ur5_like.urdf");
const JOINTS = 6;
const TOOL = { mass: 1.8, centre_of_mass: [0.03, -0.02, 0.07],
               inertia: { ixx: 0.005, ixy: 0.0003, ixz: -0.0002, iyy: 0.006, iyz: 0.0001, izz: 0.004 } };
// A compact tool (a 2 kg sphere 1 cm in radius): least squares gives it an inertia no body has.
const SPHERE = { mass: 2, centre_of_mass: [0, 0, 0.05], inertia: { ixx: 8e-5, ixy: 0, ixz: 0, iyy: 8e-5, iyz: 0, izz: 8e-5 } };
const shot = (name) => path.join(artifacts, name);
const close = (a, b, relative) => Math.abs(a - b) <= relative * Math.abs(b);

const workdir = mkdtempSync(path.join(tmpdir(), "manipid-payload-dashboard-"));
mkdirSync(artifacts, { recursive: true });

// The tools mounted as the clients' tests mount theirs (a fixed link on the tip link, tool0).
for (const [name, tool] of [["tool", TOOL], ["sphere", SPHERE]]) {
  writeFileSync(path.join(workdir, `${name}.json`), JSON.stringify(tool));
  execFileSync("python3", ["-c", [
    "import json, sys",
    "sys.path.insert(0, sys.argv[1])",
    "from robot_data import with_tool",
    "open(sys.argv[4], 'w').write(with_tool(open(sys.argv[2]).read(), 'tool0', json.load(open(sys.argv[3]))))",
  ].join("\n"), path.join(root, "clients/python/tests"), URDF, path.join(workdir, `${name}.json`), path.join(workdir, `${name}.urdf`)]);
}
const run = (...args) => execFileSync(binary, args, { cwd: workdir, stdio: ["ignore", "ignore", "pipe"] });
// Budgets of evaluations, not seconds: the same excitations on every machine.
run("excitation", "--robot", URDF, "--period", "10", "--harmonics", "5", "--duration", "20", "--seed", "1",
    "--max-evaluations", "200", "--max-seconds", "600", "--out", "exc_a.csv");
run("excitation", "--robot", URDF, "--period", "8", "--harmonics", "5", "--duration", "16", "--seed", "2",
    "--max-evaluations", "200", "--max-seconds", "600", "--out", "exc_b.csv");
const noise = ["--noise-tau-relative", "0.01", "--noise-q", "2e-5", "--quantize-q", "18"];
for (const [name, urdf, excitation, seed] of [["arm", URDF, "exc_a.csv", 1], ["tool", "tool.urdf", "exc_b.csv", 2],
                                                ["check", "tool.urdf", "exc_a.csv", 3], ["bare", URDF, "exc_b.csv", 4],
                                                ["sphere", "sphere.urdf", "exc_b.csv", 5]]) {
  run("torque", "--robot", urdf, "--in", excitation, "--with-states", ...noise, "--seed", String(seed), "--out", `${name}.csv`);
}

const { server, url } = await startServer(binary, path.join(workdir, "jobs.db"));
const browser = await launch(chromium);
const consoleErrors = [];
try {
  const post = (where, body, type = "application/json") =>
    json(`${url}${where}`, { method: "POST", headers: { "Content-Type": type }, body: type === "application/json" ? JSON.stringify(body) : body });
  const finished = async (job) => {
    for (;;) {
      const answer = await json(`${url}/v1/jobs/${job.id}?wait=20`);
      if (["succeeded", "failed", "cancelled"].includes(answer.state)) return answer;
    }
  };
  const robot = await post("/v1/robots?name=arm", readFileSync(URDF), "application/xml");
  const datasets = {};
  for (const name of ["arm", "tool", "check", "bare", "sphere"]) {
    datasets[name] = (await post(`/v1/datasets?name=${name}`, readFileSync(path.join(workdir, `${name}.csv`)), "text/csv")).id;
  }
  const arm = await finished(await post("/v1/identifications", { robot_id: robot.id, dataset_id: datasets.arm, friction: ["viscous", "coulomb"] }));
  check(arm.state === "succeeded", `the arm identified (${arm.id})`);
  const payload = await finished(await post("/v1/identifications", { payload: true, robot_id: robot.id, dataset_id: datasets.tool,
                                                                     arm_job_id: arm.id, validation_dataset_id: datasets.check }));
  const none = await finished(await post("/v1/identifications", { payload: true, robot_id: robot.id, dataset_id: datasets.bare,
                                                                  arm_job_id: arm.id }));
  check(payload.state === "succeeded" && payload.kind === "payload_identification" && none.state === "succeeded",
        `the payload identifications succeeded (${payload.id}, ${none.id})`);
  const result = payload.result;
  check(result.detected && close(result.mass, TOOL.mass, 0.01), `the API's payload: ${result.mass} kg (the tool's ${TOOL.mass})`);

  // ---- the payload card ---------------------------------------------------------------------------
  const page = await newPage(browser, consoleErrors);
  await page.goto(`${url}/jobs/${payload.id}`);
  await page.waitForSelector("body[data-ready=true]", { timeout: 120000 });
  check((await page.textContent("#job-state")).trim() === "succeeded", "the page shows the job succeeded");
  check((await page.textContent("#job dl.summary")).includes("identification of a payload"), "the summary names the kind in words");
  check(await page.getAttribute("#payload-verdict", "data-detected") === "true" &&
        (await page.textContent("#payload-verdict")).includes(`A payload of ${Number(result.mass.toPrecision(4))}`),
        `the verdict: "${(await page.textContent("#payload-verdict")).trim()}"`);
  const values = await page.$$eval("#payload-values tbody tr", (rows) => Object.fromEntries(rows.map((row) =>
    [row.dataset.quantity, { estimate: row.dataset.estimate, stdError: row.dataset.stdError, shown: row.textContent }])));
  check(Object.keys(values).join(",") === "mass,com_x,com_y,com_z,ixx,ixy,ixz,iyy,iyz,izz", "the values: mass, x, y, z, six inertia entries");
  check(Number(values.mass.estimate) === result.mass && Number(values.mass.stdError) === result.mass_std_error &&
        values.mass.shown.includes("±"), "the mass and its standard error as the API's");
  check(["x", "y", "z"].every((axis, i) => close(Number(values[`com_${axis}`].estimate), 1000 * result.centre_of_mass[i], 1e-12) &&
                                          close(Number(values[`com_${axis}`].stdError), 1000 * result.centre_of_mass_std_errors[i], 1e-12)),
        "the centre of mass and its errors in mm, as the API's in m");
  check(["ixx", "iyy", "izz"].every((entry) => Number(values[entry].estimate) === result.inertia_about_com[entry]),
        "the inertia about the centre of mass as the API's");
  check(await page.getAttribute("#arm-job-link", "href") === `/jobs/${arm.id}`, "the arm's job is linked");
  check(close(parseFloat(await page.textContent("#payload-fit-with")), 100 * result.fit.with_payload_error, 1e-2) &&
        close(parseFloat(await page.textContent("#payload-fit-arm")), 100 * result.fit.arm_only_error, 1e-2),
        "the torque error with the arm alone and with the payload, as the API's");
  check(close(parseFloat(await page.textContent("#payload-validation-with")), 100 * result.validation.with_payload.overall_relative_error, 1e-2),
        "the held-out run's error with the payload, as the API's");
  check((await page.textContent("#payload-filters")).includes(`chosen by held-out error among ${result.filters.candidates.length}`),
        "the low-pass says it was chosen by held-out error, among how many");
  check((await page.textContent("#payload-undetermined")).includes("none") === (result.undetermined.length === 0),
        "what the runs leave undetermined, as the API's");
  check(await page.getAttribute("#payload-urdf", "href") === `/v1/jobs/${payload.id}/urdf`, "a download of the URDF with the payload");
  check(await page.getAttribute("#payload-consistent", "data-consistent") === "true" && result.consistent,
        "it says the payload is a real body, as the API does");
  const urdf = await fetch(`${url}/v1/jobs/${payload.id}/urdf`).then((response) => response.text());
  check(urdf.includes('<link name="manipid_payload"'), "... which the server writes with the payload mounted");

  // ---- the centre of mass on the flange -----------------------------------------------------------
  const picture = await page.$$eval("#payload-com .com", (points) => points.map((point) => ({
    axes: point.getAttribute("data-axes"), u: Number(point.getAttribute("data-u")), v: Number(point.getAttribute("data-v")),
    cx: Number(point.getAttribute("cx")), cy: Number(point.getAttribute("cy")) })));
  const [cx, cy, cz] = result.centre_of_mass;
  check(picture.length === 2 && picture[0].axes === "xy" && picture[1].axes === "xz" &&
        picture[0].u === cx && picture[0].v === cy && picture[1].u === cx && picture[1].v === cz,
        "the point is drawn at the centre of mass from above (x, y) and from the side (x, z)");
  const plate = await page.$eval("#payload-com .view-xy .plate", (circle) => ({ cx: Number(circle.getAttribute("cx")),
                                                                              cy: Number(circle.getAttribute("cy")), r: Number(circle.getAttribute("r")) }));
  const radius = Number(await page.getAttribute("#payload-com", "data-radius"));
  const scale = plate.r / radius;
  check(Math.abs(picture[0].cx - (plate.cx + scale * cx)) < 1e-6 && Math.abs(picture[0].cy - (plate.cy - scale * cy)) < 1e-6,
        `from above: x to the right, y up, on the circle's scale (${radius * 1000} mm)`);
  check(Math.hypot(cx, cy) < radius && Math.abs(cz) < radius, "the circle holds the point");
  check(await page.locator("#payload-com ellipse.sigma").count() === 2, "each view has the two-standard-error ellipse");
  check((await page.getAttribute("#payload-com", "aria-label")).includes("centre of mass at x"), "the picture has a text alternative");
  await page.locator("#payload").screenshot({ path: shot("payload-card.png") });

  // ---- the torque with and without the payload ----------------------------------------------------
  const fit = await json(`${url}/v1/jobs/${payload.id}/fit?max_points=1000`);
  for (const view of ["fit", "validation"]) {
    const boxes = page.locator(`#payload-${view} .grid.joints > div`);
    const series = await boxes.evaluateAll((divs) => divs.map((div) => div.dataset.series));
    check(await boxes.count() === JOINTS && series.every((count) => count === "4"),
          `${view}: one chart per joint with measured, with the payload, the residual and the arm alone`);
    check(await page.locator(`#payload-${view}-table tbody tr`).count() === JOINTS, `${view}: the error per joint, with and without`);
  }
  check(await page.getAttribute("#chart-payload-fit-1", "data-points") === String(fit.t.length), "the fit's charts draw the API's points");
  const table = await page.$$eval("#payload-fit-table tbody tr", (rows) => rows.map((row) => [Number(row.dataset.withPayload), Number(row.dataset.armOnly)]));
  check(table.every(([withPayload, armOnly], j) => withPayload === fit.joints[j].relative_error && armOnly === fit.joints[j].arm_only_relative_error),
        "the per-joint errors as the API's /fit");
  check(await page.locator("#robot-data").count() === 1, "the run as measured is drawn");
  await page.locator("#payload-fit").screenshot({ path: shot("payload-fit.png") });

  // ---- keyboard, a narrow screen --------------------------------------------------------------
  check(await tabUntil(page, () => document.activeElement?.id === "payload-urdf"), "the URDF download is reachable with Tab");
  await page.setViewportSize({ width: 390, height: 800 });
  await page.waitForTimeout(300);
  check(await overflow(page) <= 1, "a narrow screen (390 px) needs no sideways scrolling");
  await page.locator("#payload").screenshot({ path: shot("payload-card-narrow.png") });
  await page.setViewportSize({ width: 1280, height: 800 });

  // ---- a run without the tool -------------------------------------------------------------------
  await page.goto(`${url}/jobs/${none.id}`);
  await page.waitForSelector("body[data-ready=true]", { timeout: 120000 });
  check(await page.getAttribute("#payload-verdict", "data-detected") === "false" &&
        (await page.textContent("#payload-verdict")).includes("not an error"), "a run without the tool: \"No payload\", not an error");
  check(await page.locator("#payload-com .com").count() === 0 && (await page.textContent("#payload-com")).includes("no payload detected"),
        "... no point on the flange, and the picture says why");
  check(await page.locator("#payload-urdf").count() === 0, "... no URDF to download");
  check((await page.textContent("#payload-warnings")).includes("no payload"), "... the warning says so");
  await page.locator("#payload").screenshot({ path: shot("payload-none.png") });

  // ---- a compact tool: not a real body; the same identification asked for one, from the page -------
  const sphere = await finished(await post("/v1/identifications", { payload: true, robot_id: robot.id, dataset_id: datasets.sphere,
                                                                    arm_job_id: arm.id }));
  check(sphere.state === "succeeded" && sphere.result.detected && !sphere.result.consistent,
        "the sphere's least-squares payload is no real body (the API)");
  await page.goto(`${url}/jobs/${sphere.id}`);
  await page.waitForSelector("body[data-ready=true]", { timeout: 120000 });
  check(await page.getAttribute("#payload-consistent", "data-consistent") === "false" &&
        (await page.textContent("#payload-consistent")).includes("positive definite"), "the card says why it is no real body");
  check(await page.locator("#payload-not-real").count() === 1 && await page.locator("#payload-urdf").count() === 0,
        "... and offers the identification over real bodies instead of a URDF");
  await page.locator("#payload").screenshot({ path: shot("payload-not-real.png") });
  await page.focus("#payload-physical");
  await page.keyboard.press("Enter");
  await page.waitForURL((address) => /\/jobs\/job_[0-9a-f]+$/.test(address.pathname) && !address.pathname.endsWith(sphere.id),
                        { timeout: 60000 });
  await page.waitForSelector("body[data-ready=true]", { timeout: 120000 });
  const again = await json(`${url}/v1/jobs/${page.url().split("/").pop()}`);
  check(again.request.physical === true && again.request.dataset_id === datasets.sphere && again.request.arm_job_id === arm.id,
        "the button submitted the same request with physical: true");
  check(again.result.consistent && await page.getAttribute("#payload-consistent", "data-consistent") === "true" &&
        (await page.textContent("#payload-consistent")).includes("more squared residual"),
        "its page: a real body, and what that cost the fit");
  check(await page.locator("#payload-urdf").count() === 1, "... with its URDF to download");

  // ---- the job list ----------------------------------------------------------------------------
  await page.goto(`${url}/`);
  await page.waitForSelector(`#jobs tr[data-job-id="${payload.id}"]`);
  await page.selectOption("#filter-kind", "payload_identification");
  await page.waitForFunction((ids) => {
    const rows = [...document.querySelectorAll("#jobs tbody tr")];
    return rows.length === 4 && ids.every((id) => rows.some((row) => row.dataset.jobId === id)) &&
           rows.every((row) => row.querySelector("td:nth-child(2)")?.textContent === "payload_identification");
  }, [payload.id, none.id, sphere.id], { timeout: 10000 });
  check(true, "the job list's kind filter finds the four payload identifications");

  check(consoleErrors.length === 0, `no console errors${consoleErrors.length ? ": " + consoleErrors.join(" | ") : ""}`);
} catch (error) {
  check(false, `unexpected: ${error.stack || error}`);
} finally {
  await browser.close();
  check(await stopServer(server) === 0, "the server exits 0 on SIGTERM");
  rmSync(workdir, { recursive: true, force: true });
}
console.log(failed() ? `${failed()} check(s) failed; screenshots in ${artifacts}` : `all checks passed; screenshots in ${artifacts}`);
process.exit(failed() ? 1 : 0);

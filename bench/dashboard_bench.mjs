// dashboard_bench.mjs — is the dashboard still responsive with a long history? Runs one
// identification that makes N cost evaluations (default 100,000: Subplex with zero
// tolerances on a short paper run), opens its job page in headless Chromium while it runs and
// again when it is done, and prints:
//   - the server's time for the drawing view of the history (?max_points=2000) and for the
//     whole history as CSV, at N evaluations;
//   - a live refresh of the page at full length (fetch + redraw of the cost and 8 parameter
//     charts, as a running job's page does every second), and the longest stall of the page's
//     main thread meanwhile (a 50 ms timer's worst lateness);
//   - the finished page's load time, to every chart drawn.
// Figures only, no pass/fail: speed belongs in notes, not tests.
//
//   cmake --workflow --preset release && node bench/dashboard_bench.mjs build/release/server/manipid [N]
import { spawn } from "node:child_process";
import { mkdtempSync, rmSync } from "node:fs";
import { createRequire } from "node:module";
import { tmpdir } from "node:os";
import path from "node:path";
import readline from "node:readline";
import { fileURLToPath } from "node:url";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const { chromium } = createRequire(path.join(root, "web/package.json"))("playwright-core");
const binary = process.argv[2] || "build/release/server/manipid";
const evaluations = Number(process.argv[3] || 100000);

const workdir = mkdtempSync(path.join(tmpdir(), "manipid-dashboard-bench-"));
const server = spawn(binary, ["serve", "--port", "0", "--db", path.join(workdir, "jobs.db"), "--workers", "1"],
                     { stdio: ["ignore", "pipe", "ignore"] });
const url = /listening on (\S+)/.exec(await new Promise((resolve) => readline.createInterface({ input: server.stdout }).once("line", resolve)))[1];
const call = async (p, init) => {
  const response = await fetch(url + p, init);
  if (!response.ok) throw new Error(`${p}: ${response.status} ${await response.text()}`);
  return (response.headers.get("content-type") || "").includes("json") ? response.json() : response.text();
};
const median = (values) => { const s = [...values].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };
const timed = async (f) => { const t = performance.now(); await f(); return performance.now() - t; };

const job = await call("/v1/identifications", {
  method: "POST", headers: { "Content-Type": "application/json" },
  body: JSON.stringify({ simulation: { duration: 2.0 }, half_length: 100, band: 0.2, algorithm: "LN_SBPLX",
                         max_evaluations: evaluations, relative_x_tolerance: 0, relative_f_tolerance: 0, max_seconds: 600 }),
});
const browser = await chromium.launch({ executablePath: "/usr/bin/chromium",
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update", "--disable-sync"] });
const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
const errors = [];
page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });

// Live: the page polls every second while the job runs; sample its refresh times and the main
// thread's worst stall.
await page.goto(`${url}/jobs/${job.id}`);
await page.evaluate(() => {
  window.__lag = 0;
  let last = performance.now();
  setInterval(() => { const now = performance.now(); window.__lag = Math.max(window.__lag, now - last - 50); last = now; }, 50);
});
const refreshes = [];
let seenTotal = 0;
for (;;) {
  const state = await call(`/v1/jobs/${job.id}`);
  const box = await page.$("#chart-cost");
  if (box) {
    const total = Number(await box.getAttribute("data-total"));
    if (total !== seenTotal) { seenTotal = total; refreshes.push({ total, ms: Number(await box.getAttribute("data-draw-ms")) }); }
  }
  if (["succeeded", "failed", "cancelled"].includes(state.state)) break;
  await new Promise((r) => setTimeout(r, 500));
}
await page.waitForSelector("body[data-ready=true]", { timeout: 120000 });
const lag = await page.evaluate(() => window.__lag);
const done = await call(`/v1/jobs/${job.id}`);

// The server's side at the full length.
const overviewMs = [], csvMs = [];
let csvBytes = 0;
for (let i = 0; i < 10; i += 1) {
  overviewMs.push(await timed(() => call(`/v1/jobs/${job.id}/history?max_points=2000`)));
  csvMs.push(await timed(async () => { csvBytes = (await call(`/v1/jobs/${job.id}/history?format=csv`)).length; }));
}

// The finished page, loaded fresh.
const loads = [];
for (let i = 0; i < 5; i += 1) {
  loads.push(await timed(async () => {
    await page.goto(`${url}/jobs/${job.id}`);
    await page.waitForSelector("body[data-ready=true]", { timeout: 120000 });
  }));
}
const drawMs = Number(await page.getAttribute("#chart-cost", "data-draw-ms"));

// Live refreshes at full length (what a running job's page does every second): fetch the
// drawing view and redraw the 9 charts, 20 times, watching the main thread meanwhile.
const live = await page.evaluate(async () => {
  let lag = 0, last = performance.now();
  const timer = setInterval(() => { const now = performance.now(); lag = Math.max(lag, now - last - 50); last = now; }, 50);
  const times = [];
  for (let i = 0; i < 20; i += 1) {
    const started = performance.now();
    await window.manipidJob.refreshHistory();
    times.push(performance.now() - started);
    await new Promise((r) => setTimeout(r, 100));
  }
  clearInterval(timer);
  return { times, lag };
});
console.log(`job ${job.id}: ${done.state}, ${done.result?.evaluations} evaluations in ${done.result?.wall_seconds?.toFixed(1)} s`);
console.log(`history, drawing view (?max_points=2000): median ${median(overviewMs).toFixed(1)} ms, max ${Math.max(...overviewMs).toFixed(1)} ms`);
console.log(`history, whole as CSV: ${(csvBytes / 1e6).toFixed(1)} MB, median ${median(csvMs).toFixed(0)} ms`);
console.log(`while the job ran: ${refreshes.length} refreshes seen (${refreshes.map((r) => `${r.total}: ${r.ms} ms`).join(", ")}); main thread's worst stall ${lag.toFixed(0)} ms`);
console.log(`live refresh at ${done.result?.evaluations} evaluations (fetch + redraw of 9 charts), 20 times: median ${median(live.times).toFixed(0)} ms, max ${Math.max(...live.times).toFixed(0)} ms; main thread's worst stall ${live.lag.toFixed(0)} ms`);
console.log(`finished page, load to every chart drawn: median ${median(loads).toFixed(0)} ms (history part ${drawMs} ms)`);
console.log(`console errors: ${errors.length}`);
await browser.close();
server.kill("SIGTERM");
await new Promise((r) => server.once("exit", r));
rmSync(workdir, { recursive: true, force: true });

// support.mjs — what the dashboard's end-to-end tests share: the skip rules (exit 77 without
// Debian's chromium or web/node_modules), the ok/FAIL log, `manipid serve --port 0` on a fresh
// SQLite file, and a headless Chromium that records console errors.
import { spawn } from "node:child_process";
import { existsSync } from "node:fs";
import { createRequire } from "node:module";
import path from "node:path";
import readline from "node:readline";
import { fileURLToPath } from "node:url";

export const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../..");
export const CHROMIUM = process.env.CHROMIUM || "/usr/bin/chromium";

function skip(why) { console.log(`SKIP: ${why}`); process.exit(77); }

/** playwright-core's chromium, or exit 77 (skipped) when the test cannot run here. */
export function chromiumOrSkip() {
  if (!existsSync(CHROMIUM)) skip(`${CHROMIUM} not found (Debian package chromium; scripts/setup.sh installs it)`);
  try {
    return createRequire(path.join(root, "web/package.json"))("playwright-core").chromium;
  } catch {
    return skip("playwright-core is not in web/node_modules (run `npm ci --prefix web`; scripts/setup.sh does)");
  }
}

let failures = 0;
export function check(condition, what) {
  console.log(`${condition ? "ok  " : "FAIL"}  ${what}`);
  if (!condition) failures += 1;
  return condition;
}
export const failed = () => failures;

export async function startServer(binary, database) {
  const server = spawn(binary, ["serve", "--port", "0", "--db", database, "--workers", "2"], { stdio: ["ignore", "pipe", "pipe"] });
  server.stderr.on("data", () => {});  // request log
  const line = await new Promise((resolve, reject) => {
    readline.createInterface({ input: server.stdout }).once("line", resolve);
    server.once("exit", (code) => reject(new Error(`manipid serve exited with ${code} before listening`)));
  });
  const url = /listening on (http:\/\/\S+)/.exec(line)?.[1];
  if (!url) throw new Error(`unexpected first line: ${line}`);
  return { server, url };
}

export async function stopServer(server) {
  server.kill("SIGTERM");
  return new Promise((resolve) => server.once("exit", resolve));
}

export function launch(chromium) {
  return chromium.launch({
    executablePath: CHROMIUM,
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
           "--disable-component-update", "--disable-sync"],
  });
}

/** A page that pushes console errors and uncaught exceptions into `errors`. */
export async function newPage(browser, errors, viewport = { width: 1280, height: 800 }) {
  const page = await browser.newPage({ viewport });
  page.on("console", (message) => { if (message.type() === "error") errors.push(message.text()); });
  page.on("pageerror", (error) => errors.push(String(error)));
  return page;
}

export async function json(url, init) {
  const response = await fetch(url, init);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status} ${await response.text()}`);
  return response.json();
}

/** Presses Tab until `predicate` (run in the page) holds; true when it did within `limit` presses. */
export async function tabUntil(page, predicate, argument, limit = 150) {
  for (let presses = 0; presses < limit; presses += 1) {
    await page.keyboard.press("Tab");
    if (await page.evaluate(predicate, argument)) return true;
  }
  return false;
}

/** Sideways scrolling the page needs at its current viewport (0: none). */
export function overflow(page) {
  return page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
}

/** The range a chart's axis shows ("x" or "y"), from its data-x-range / data-y-range: [min, max], or null. */
export async function axisRange(page, selector, axis) {
  const text = await page.getAttribute(selector, `data-${axis}-range`);
  return text ? text.split(" ").map(Number) : null;
}

/** Drags the mouse across a chart's plot from `from` to `to` (fractions of its width), as a reader zooms. */
export async function dragAcross(page, selector, from, to) {
  const over = page.locator(`${selector} .u-over`);
  await over.scrollIntoViewIfNeeded();
  const box = await over.boundingBox();
  const y = box.y + box.height / 2;
  await page.mouse.move(box.x + from * box.width, y);
  await page.mouse.down();
  await page.mouse.move(box.x + to * box.width, y, { steps: 8 });
  await page.mouse.up();
}

// app.js — the dashboard's entry point: routes / (jobs and the paper's form), /jobs/{id} (one
// job), /robots (the robots) and /robots/{id} (one robot) with the History API, so every
// page has an address to bookmark and Back works.
import { onTokenNeeded, setToken } from "./api.js";
import { forgetDetachedCharts } from "./charts.js";
import { h } from "./dom.js";
import { jobView } from "./job_page.js";
import { jobsListView } from "./jobs_list.js";
import { isView, viewOf } from "./paths.js";
import { robotView, robotsListView } from "./robots.js";

const main = document.getElementById("main");
const ID = "([A-Za-z0-9_-]{1,64})";
let shown = null;  // the view on the page, so an in-page anchor (#main) does not redraw it

async function render() {
  const view = viewOf(location);
  shown = view;
  document.body.dataset.ready = "false";  // each view says "true" when it has drawn everything
  const job = new RegExp(`^/jobs/${ID}$`).exec(view);
  const robot = new RegExp(`^/robots/${ID}$`).exec(view);
  try {
    if (job) await jobView(main, job[1]);
    else if (robot) await robotView(main, robot[1], navigate);
    else if (view === "/robots" || view === "/robots/") await robotsListView(main, navigate);
    else if (view === "/" || view === "/index.html") await jobsListView(main, navigate);
    else main.replaceChildren(h("h1", {}, "Not found"), h("p", {}, h("a", { href: "/" }, "Back to the jobs")));
  } catch (error) {
    main.replaceChildren(h("h1", {}, "Something went wrong"), h("p", { role: "alert" }, error.message || String(error)),
                         h("p", {}, h("a", { href: "/" }, "Back to the jobs")));
  } finally {
    forgetDetachedCharts();
  }
}

export function navigate(path) {
  history.pushState(null, "", path);
  render();
  main.focus();
}

// Same-origin links to views stay in the page; the API links (/v1, /openapi.json), downloads
// and in-page anchors (#main) do not.
document.addEventListener("click", (event) => {
  const link = event.target.closest("a[href]");
  if (!link || event.defaultPrevented || event.button !== 0 || event.metaKey || event.ctrlKey || event.shiftKey) return;
  if (link.hasAttribute("download")) return;
  const url = new URL(link.href, location.href);
  if (url.origin === location.origin && url.pathname === location.pathname && !isView(url)) {
    // An in-page anchor (#main, #identifiability): go there without touching the address, which
    // may itself be an old fragment address (/#/robots).
    const target = document.getElementById(decodeURIComponent(url.hash.slice(1)));
    if (!target) return;
    event.preventDefault();
    if (!target.hasAttribute("tabindex")) target.setAttribute("tabindex", "-1");
    target.focus({ preventScroll: true });
    target.scrollIntoView();
    return;
  }
  if (url.origin !== location.origin || url.pathname.startsWith("/v1/") || url.pathname.endsWith(".json") || !isView(url)) return;
  event.preventDefault();
  navigate(url.pathname + url.hash);
});
// Back, Forward, and an address edited by hand (/robots): redraw when the view changed.
const follow = () => { if (viewOf(location) !== shown) render(); };
window.addEventListener("popstate", follow);
window.addEventListener("hashchange", follow);

const tokenForm = document.getElementById("token-form");
onTokenNeeded(() => { tokenForm.hidden = false; document.getElementById("token-input").focus(); });
tokenForm.addEventListener("submit", (event) => {
  event.preventDefault();
  setToken(document.getElementById("token-input").value.trim());
  tokenForm.hidden = true;
  render();
});

// uPlot arrives by a deferred classic script, which runs before module scripts; check anyway.
if (typeof uPlot === "undefined") {
  main.replaceChildren(h("p", { role: "alert" }, "The chart library did not load."));
} else {
  render();
}

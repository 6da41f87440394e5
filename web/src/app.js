// app.js — the dashboard's entry point: routes / (jobs and the paper's form) and /jobs/{id}
// (one job) with the History API, so every page has an address to bookmark and Back works.
import { onTokenNeeded, setToken } from "./api.js";
import { forgetDetachedCharts } from "./charts.js";
import { h } from "./dom.js";
import { jobView } from "./job_page.js";
import { jobsListView } from "./jobs_list.js";

const main = document.getElementById("main");

async function render() {
  const path = location.pathname;
  const job = /^\/jobs\/([A-Za-z0-9_-]{1,64})$/.exec(path);
  try {
    if (job) await jobView(main, job[1]);
    else if (path === "/" || path === "/index.html") await jobsListView(main, navigate);
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

// Same-origin links to views stay in the page; the API links (/v1, /openapi.json) do not.
document.addEventListener("click", (event) => {
  const link = event.target.closest("a[href]");
  if (!link || event.defaultPrevented || event.button !== 0 || event.metaKey || event.ctrlKey || event.shiftKey) return;
  const url = new URL(link.href, location.href);
  if (url.origin !== location.origin || url.pathname.startsWith("/v1/") || url.pathname.endsWith(".json")) return;
  event.preventDefault();
  navigate(url.pathname);
});
window.addEventListener("popstate", render);

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

// paths.js — the dashboard's addresses. The server hands the page out at / and /jobs/{id}
// only, so the robot views live in the fragment (/#/robots, /#/robots/{id}): bookmarkable and
// reloadable without a server change. viewOf() also accepts /robots and /robots/{id} as paths,
// so the day the server routes them to the page, only ROBOTS below changes.

export const ROBOTS = "/#/robots";
export const robotPath = (id) => `${ROBOTS}/${encodeURIComponent(id)}`;
export const jobPath = (id) => `/jobs/${encodeURIComponent(id)}`;

/** The view an address names: "/", "/jobs/{id}", "/robots", "/robots/{id}", or its path. */
export function viewOf(url) {
  const fragment = url.hash.startsWith("#/") ? url.hash.slice(1) : "";
  return url.pathname === "/" && fragment ? fragment : url.pathname;
}

/** An address the page draws itself (a fragment that is not a view is an in-page anchor). */
export function isView(url) {
  return url.hash === "" || url.hash.startsWith("#/");
}

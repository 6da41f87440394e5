// paths.js — the dashboard's addresses: /, /jobs/{id}, /robots and /robots/{id}, each handed
// the page by the server (api/src/http/route_table.cpp). Older fragment addresses
// (/#/robots, /#/robots/{id}) still open their view.

export const ROBOTS = "/robots";
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

// api.js — the dashboard's calls to the manipid API: JSON in and out, problem+json errors
// thrown as ApiProblem (with the field at fault), and the bearer token when the server wants one.

const TOKEN_KEY = "manipid.token";

export class ApiProblem extends Error {
  constructor(problem, status) {
    super(problem.detail || problem.title || `HTTP ${status}`);
    this.status = status;
    this.code = problem.code || "";
    this.field = problem.field || "";
  }
}

let askForToken = () => {};
/** Called with a retry function when the server answers 401. */
export function onTokenNeeded(callback) { askForToken = callback; }
export function setToken(token) { sessionStorage.setItem(TOKEN_KEY, token); }

/**
 * A call to the API. `body`: an object sent as JSON, or — with `type`, its media type — sent as it
 * is (a File or a string: a CSV upload).
 */
export async function api(path, { method = "GET", body, type } = {}) {
  const headers = { Accept: "application/json" };
  const token = sessionStorage.getItem(TOKEN_KEY);
  if (token) headers.Authorization = `Bearer ${token}`;
  if (body !== undefined) headers["Content-Type"] = type || "application/json";
  const sent = body === undefined || type ? body : JSON.stringify(body);
  const response = await fetch(path, { method, headers, body: sent });
  const answered = response.headers.get("Content-Type") || "";
  const payload = answered.includes("json") ? await response.json() : await response.text();
  if (response.status === 401) askForToken();
  if (!response.ok) throw new ApiProblem(typeof payload === "object" ? payload : { detail: payload }, response.status);
  return payload;
}

/**
 * A link that downloads `href` (a file from the API). A plain link cannot carry the bearer
 * token, so with one set the click fetches the file with it and saves what came back.
 */
export function downloadLink(href, label, { filename = "", ...attributes } = {}) {
  const link = document.createElement("a");
  link.href = href;
  link.setAttribute("download", filename);
  for (const [name, value] of Object.entries(attributes)) link.setAttribute(name, value);
  link.append(label);
  link.addEventListener("click", async (event) => {
    const token = sessionStorage.getItem(TOKEN_KEY);
    if (!token) return;
    event.preventDefault();
    const response = await fetch(href, { headers: { Authorization: `Bearer ${token}` } });
    if (response.status === 401) { askForToken(); return; }
    if (!response.ok) return;
    const named = /filename="([^"]+)"/.exec(response.headers.get("Content-Disposition") || "")?.[1];
    const url = URL.createObjectURL(await response.blob());
    const save = Object.assign(document.createElement("a"), { href: url, download: filename || named || "" });
    document.body.append(save);
    save.click();
    save.remove();
    setTimeout(() => URL.revokeObjectURL(url), 10000);
  });
  return link;
}

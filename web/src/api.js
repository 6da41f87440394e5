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

export async function api(path, { method = "GET", body } = {}) {
  const headers = { Accept: "application/json" };
  const token = sessionStorage.getItem(TOKEN_KEY);
  if (token) headers.Authorization = `Bearer ${token}`;
  if (body !== undefined) headers["Content-Type"] = "application/json";
  const response = await fetch(path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
  const type = response.headers.get("Content-Type") || "";
  const payload = type.includes("json") ? await response.json() : await response.text();
  if (response.status === 401) askForToken();
  if (!response.ok) throw new ApiProblem(typeof payload === "object" ? payload : { detail: payload }, response.status);
  return payload;
}

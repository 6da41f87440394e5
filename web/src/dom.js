// dom.js — a tiny element builder and formatting helpers shared by the views.

/** h("a", {href: "/"}, "text", child, ...): attributes starting with "on" are listeners. */
export function h(tag, attributes = {}, ...children) {
  const element = document.createElement(tag);
  for (const [name, value] of Object.entries(attributes || {})) {
    if (value === undefined || value === null || value === false) continue;
    if (name.startsWith("on") && typeof value === "function") element.addEventListener(name.slice(2), value);
    else if (name === "dataset") Object.assign(element.dataset, value);
    else if (value === true) element.setAttribute(name, "");
    else element.setAttribute(name, String(value));
  }
  for (const child of children.flat(Infinity)) {
    if (child === undefined || child === null || child === false) continue;
    element.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return element;
}

/** A number with `digits` significant digits, or "–" when absent. */
export function number(value, digits = 6) {
  if (value === null || value === undefined || Number.isNaN(value)) return "–";
  if (value === 0) return "0";
  const magnitude = Math.abs(value);
  if (magnitude >= 1e-3 && magnitude < 1e6) return String(Number(value.toPrecision(digits)));
  return value.toExponential(Math.max(0, digits - 1));
}

export function when(timestamp) {
  if (!timestamp) return "–";
  const date = new Date(timestamp);
  return Number.isNaN(date.getTime()) ? timestamp : date.toLocaleString();
}

export function stateBadge(state) {
  return h("span", { class: `badge state-${state}`, dataset: { state } }, state);
}

/** A card with a heading that labels it: section("fit", "Torque fit", ...children). */
export function section(id, title, ...children) {
  return h("section", { id, class: "card", "aria-labelledby": `${id}-title` }, h("h2", { id: `${id}-title` }, title), ...children);
}

/** A definition list of [term, detail] pairs; pairs whose detail is null or undefined are left out. */
export function facts(pairs, attributes = {}) {
  return h("dl", { class: "summary", ...attributes },
    pairs.filter(([, detail]) => detail !== null && detail !== undefined)
      .map(([term, detail]) => [h("dt", {}, term), h("dd", {}, detail)]));
}

/** A fraction as a percentage with `digits` significant digits ("0.0632 %"), or "–". */
export function percent(fraction, digits = 3) {
  if (fraction === null || fraction === undefined || Number.isNaN(fraction)) return "–";
  return `${number(100 * fraction, digits)} %`;
}

/** "1 joint", "7 joints". */
export function plural(count, noun, nouns = `${noun}s`) {
  return `${count} ${count === 1 ? noun : nouns}`;
}

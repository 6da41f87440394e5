// charts.js — line charts over uPlot (loaded as the global `uPlot` by index.html). Every chart
// fills its container's width, follows resizes, and records what it draws in data-points and
// data-series on its container (for people reading the DOM, and for the end-to-end test).
// Series arrive already thinned by the server (max_points), so drawing stays cheap whatever
// the length of a history.

export const PALETTE = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"];

const charts = new Set();
let resizeObserver = null;

function observe(chart) {
  if (!resizeObserver) {
    resizeObserver = new ResizeObserver((entries) => {
      for (const entry of entries) {
        for (const each of charts) {
          if (each.container === entry.target) {
            const width = Math.max(200, Math.floor(entry.contentRect.width));
            if (width !== each.plot.width) each.plot.setSize({ width, height: each.height });
          }
        }
      }
    });
  }
  resizeObserver.observe(chart.container);
}

/** Removes charts whose containers left the page (after a view change). */
export function forgetDetachedCharts() {
  for (const chart of charts) {
    if (!chart.container.isConnected) {
      resizeObserver?.unobserve(chart.container);
      chart.plot.destroy();
      charts.delete(chart);
    }
  }
}

function record(container, data) {
  container.dataset.points = String(data[0].length);
  container.dataset.series = String(data.length - 1);
}

/**
 * The y ticks of a log axis: 1, 2, …, 9 or 1, 2, 5 times each power of ten when a decade is
 * tall enough, else every `step`th power of ten, so that ticks stay LOG_TICK_SPACE CSS pixels
 * apart or more; bounded by the axis's height whatever the range. Not uPlot's own log splits:
 * in uPlot 1.6.32 they never end once the scale reaches below about 1e-25 (9e-26 + 1e-26 is
 * 1.0000000000000002e-25, not in its table of increments, so it is rounded to 0 decimals,
 * i.e. to 0, and the loop pushes 0 until the array is too long: "RangeError: Invalid array
 * length"). An output-error cost on noise-free data converges to about 1e-27.
 */
const LOG_TICK_SPACE = 30;  // CSS pixels; uPlot's default space between y ticks
function logSplits(u, axisIdx, min, max) {
  if (!(min > 0) || !(max >= min) || max === Infinity) return [];
  const scale = u.axes[axisIdx].scale;
  const low = Math.floor(Math.log10(min)), high = Math.floor(Math.log10(max));
  const decadePx = Math.abs(u.valToPos(Number(`1e${low}`), scale) - u.valToPos(Number(`1e${low + 1}`), scale));
  const fits = (fraction) => Number.isFinite(decadePx) && fraction * decadePx >= LOG_TICK_SPACE;
  // The closest ticks of each set are log10(10/9), log10(2) (and log10(2.5)) decades apart.
  const mantissas = fits(Math.log10(10 / 9)) ? [1, 2, 3, 4, 5, 6, 7, 8, 9] : fits(Math.log10(2)) ? [1, 2, 5] : [1];
  const step = mantissas.length > 1 || !(decadePx > 0 && decadePx < Infinity)
    ? 1 : Math.max(1, Math.ceil(LOG_TICK_SPACE / decadePx));
  if ((high - low) / step > 1000) return [];  // cannot happen with finite doubles; a bound all the same
  const splits = [];
  for (let exponent = Math.floor(low / step) * step; exponent <= high; exponent += step) {
    for (const mantissa of mantissas) {
      const value = Number(`${mantissa}e${exponent}`);
      if (value >= min && value <= max) splits.push(value);
    }
  }
  return splits;
}

/**
 * A line chart in `container`. `series`: [{label, color?, dash?, width?, show?, points?}], `data`: [x, y1, y2, ...];
 * a series with `points: true` is drawn as dots, not joined (a scatter; x must still ascend).
 * Options: xLabel, yLabel, logY, height, sync (charts with the same key share the cursor: small
 * multiples over the same time axis), legend (false: none, for small multiples with one key).
 */
export function lineChart(container, { title, xLabel, yLabel, series, data, logY = false, height = 240, sync, legend = true }) {
  container.classList.add("chart");
  container.setAttribute("role", "img");
  container.setAttribute("aria-label", `${title}: ${series.map((s) => s.label).join(", ")} against ${xLabel}`);
  const width = Math.max(200, Math.floor(container.clientWidth || 600));
  const options = {
    title,
    width,
    height,
    scales: { x: { time: false }, y: logY ? { distr: 3 } : {} },
    axes: [
      { label: xLabel, stroke: "#333", grid: { stroke: "#e5e5e5" } },
      { label: yLabel, stroke: "#333", grid: { stroke: "#e5e5e5" }, size: 70,
        ...(logY ? { splits: logSplits, filter: (_, splits) => splits,
                     values: (_, splits) => splits.map((v) => (v == null ? "" : v.toExponential(0))) } : {}) },
    ],
    series: [
      { label: xLabel },
      ...series.map((s, i) => ({
        label: s.label,
        stroke: s.color || PALETTE[i % PALETTE.length],
        width: s.width || 1.5,
        dash: s.dash,
        show: s.show !== false,
        ...(s.points
          ? { paths: () => null, points: { show: true, size: 3, width: 0, fill: s.color || PALETTE[i % PALETTE.length] } }
          : { points: { show: false } }),
      })),
    ],
    legend: { show: legend },
    cursor: sync ? { drag: { x: true, y: false }, sync: { key: sync } } : { drag: { x: true, y: false } },
  };
  const plot = new uPlot(options, data, container);
  const chart = { container, plot, height };
  charts.add(chart);
  observe(chart);
  record(container, data);
  return {
    update(next) {
      plot.setData(next);
      record(container, next);
    },
    /** Shows or hides series i (0-based, as in `series`); the y axis fits what is shown. */
    showSeries(i, show) {
      plot.setSeries(i + 1, { show });
    },
  };
}

/**
 * Positive values only, for a log axis: anything else becomes a gap — and so do subnormal
 * numbers and infinities, whose decade (10 ** floor(log10 v)) is 0 or Infinity and would
 * leave the log scale without a finite, positive range.
 */
export function positive(values) {
  return values.map((v) => (typeof v === "number" && v >= 1e-300 && v < Infinity ? v : null));
}

// charts.js — line charts over uPlot (loaded as the global `uPlot` by index.html). Every chart
// fills its container's width, follows resizes, and records what it draws in data-points and
// data-series on its container, and the ranges its axes show in data-x-range and data-y-range
// ("min max"; for people reading the DOM, and for the end-to-end tests). Series arrive already
// thinned by the server (max_points), so drawing stays cheap whatever the length of a history.
//
// A chart's axes move only when the reader moves them. Drag across a chart: its x axis zooms to
// the stretch dragged (charts side by side over one time axis, `sync`, zoom together) and y fits
// what that stretch shows. Double-click: the whole x range again, y fitted to the series shown.
// Nothing else moves them:
// - a series hidden from the legend leaves both axes where they are (the other curves stay put;
//   double-click to fit y to what is left); one shown again widens y only as far as it needs;
// - new data of a live chart (update) keep a zoomed window, and y while a series is hidden from
//   the legend; an unzoomed live chart's x axis follows its data as they grow;
// - a resize keeps the window.
// The one exception is a chart's own switch between quantities (showSeries: the torques or their
// residual): y fits the quantity shown.

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

/** The smallest and largest values series i (uPlot's index) takes in the x window shown. */
function extent(u, i) {
  const x = u.data[0], values = u.data[i], { min, max } = u.scales.x;
  let low = Infinity, high = -Infinity;
  for (let k = 0; k < x.length; k += 1) {
    const v = values[k];
    if (x[k] < min || x[k] > max || typeof v !== "number" || !Number.isFinite(v)) continue;
    if (v < low) low = v;
    if (v > high) high = v;
  }
  return low <= high ? [low, high] : [u.scales.y.min, u.scales.y.max];
}

/** The range a scale shows, "min max", as data-x-range and data-y-range say it. */
function recordRange(container, key, scale) {
  container.dataset[`${key}Range`] = scale.min == null || scale.max == null ? "" : `${scale.min} ${scale.max}`;
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
  // Series (uPlot's index, 1-based) hidden from the legend, and whether showSeries is switching
  // quantities (the one change of series that refits y).
  const hiddenFromLegend = new Set();
  let switching = false;
  let lastY = null;  // the last y range drawn
  const fit = (low, high) => (logY ? uPlot.rangeLog(low, high, 10, false) : uPlot.rangeNum(low, high, 0.1, true));
  container.classList.add("chart");
  container.setAttribute("role", "img");
  container.setAttribute("aria-label", `${title}: ${series.map((s) => s.label).join(", ")} against ${xLabel}`);
  const width = Math.max(200, Math.floor(container.clientWidth || 600));
  const options = {
    title,
    width,
    height,
    // y: uPlot's own fit (its defaults for a linear and a log scale), except with nothing to fit
    // — every series hidden, or no value in the window — where uPlot would drop the y axis and
    // widen the plot into its place: the last range drawn stays instead.
    scales: { x: { time: false },
              y: { ...(logY ? { distr: 3 } : {}),
                   range: (u, low, high) => (low == null || high == null ? (lastY ? [lastY.min, lastY.max] : logY ? [1, 10] : [0, 1])
                                                                          : fit(low, high)) } },
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
    hooks: {
      // A series shown or hidden from the legend: uPlot would fit y to the series left (the
      // remaining curves jump); keep the range shown instead. uPlot fires this hook before it
      // applies the pending fit, so the scale still holds the range on screen.
      setSeries: [(u, i, opts) => {
        if (opts.show == null || switching || i == null) return;
        if (opts.show) hiddenFromLegend.delete(i); else hiddenFromLegend.add(i);
        const { min, max } = u.scales.y;
        if (min == null || max == null) return;  // nothing was shown: let uPlot fit what is
        // Shown again: widen y only as far as the series needs (it is never cut off).
        const [low, high] = opts.show ? extent(u, i) : [min, max];
        const fitted = low >= min && high <= max ? [min, max] : fit(low, high);
        u.setScale("y", { min: Math.min(min, fitted[0]), max: Math.max(max, fitted[1]) });
      }],
      setScale: [(u, key) => {
        if (key === "y" && u.scales.y.min != null) lastY = { min: u.scales.y.min, max: u.scales.y.max };
        if (key === "x" || key === "y") recordRange(container, key, u.scales[key]);
      }],
    },
  };
  const plot = new uPlot(options, data, container);
  const chart = { container, plot, height };
  charts.add(chart);
  observe(chart);
  record(container, data);
  return {
    /**
     * New data (a live job's refresh). Unzoomed, with every series the legend shows, the axes
     * follow the data; zoomed in, the window stays (y fitted to it); with a series hidden from
     * the legend, y stays too.
     */
    update(next) {
      const { x, y } = plot.scales;
      const before = plot.data[0];
      const zoomed = before.length > 1 && x.min != null && (x.min > before[0] || x.max < before[before.length - 1]);
      const keepY = hiddenFromLegend.size > 0 && y.min != null && y.max != null;
      if ((!zoomed && !keepY) || !next[0].length) {
        plot.setData(next);
      } else {
        const range = zoomed ? { min: x.min, max: x.max } : { min: next[0][0], max: next[0][next[0].length - 1] };
        const shown = { min: y.min, max: y.max };
        plot.setData(next, false);
        plot.setScale("x", range);
        if (keepY) plot.setScale("y", shown);
      }
      record(container, next);
    },
    /** Shows or hides series i (0-based, as in `series`): a switch of quantity, so y fits what is shown. */
    showSeries(i, show) {
      switching = true;
      try {
        plot.setSeries(i + 1, { show });
      } finally {
        switching = false;
      }
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

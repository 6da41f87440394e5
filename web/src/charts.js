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
 * A line chart in `container`. `series`: [{label, color?, dash?, width?, show?}], `data`: [x, y1, y2, ...].
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
        values: logY ? (_, splits) => splits.map((v) => (v == null ? "" : v.toExponential(0))) : undefined },
    ],
    series: [
      { label: xLabel },
      ...series.map((s, i) => ({
        label: s.label,
        stroke: s.color || PALETTE[i % PALETTE.length],
        width: s.width || 1.5,
        dash: s.dash,
        show: s.show !== false,
        points: { show: false },
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

/** Positive values only, for a log axis: anything else becomes a gap. */
export function positive(values) {
  return values.map((v) => (typeof v === "number" && v > 0 ? v : null));
}

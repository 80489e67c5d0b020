/* plots.js -- the page's charts: thin wrappers around uPlot (web/vendor/uPlot.iife.min.js).
 *
 * Each chart is described by a "figure": {title, xLabel, yLabel, xLog, yLog, series:[{name, x[],
 * y[], err[]?, color, dash?, fill?, points?}], bands?:[{hi, lo, fill}], marks:[…], xRange?, yClamp?, yZero?}. draw(el, fig) joins the
 * series on one x axis (uPlot.join), draws them, adds the marks (vertical lines and labelled
 * points, drawn on the canvas so that they appear in the PNG too) and keeps the chart as wide as
 * its box. The legend under each chart is uPlot's live legend: hovering reads out every series at
 * the cursor. toPNG(el) renders title + chart + legend into one PNG blob.
 */
"use strict";

const LJPlots = (() => {
  const charts = new WeakMap(); /* element -> {u, fig, ro} */
  const HEIGHT = 300;

  /* Short, exact enough numbers for readouts: 5 significant digits, exponent when far from 1. */
  function fmt(v, digits = 5) {
    if (v === null || v === undefined || !Number.isFinite(v)) return "—";
    const a = Math.abs(v);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) return v.toExponential(digits - 1);
    return String(Number(v.toPrecision(digits)));
  }

  function errFmt(v) {
    if (v === null || v === undefined || !Number.isFinite(v)) return "—";
    return v.toExponential(1);
  }

  /* Canvas marks: {type:"vline", x, label, color, dash} or {type:"point", x, y, label, color}. */
  function drawMarks(u, marks, k = 1) {
    const ctx = u.ctx;
    const dpr = (devicePixelRatio || 1) * k;
    const { left, top, width, height } = u.bbox;
    ctx.save();
    ctx.font = `${12 * dpr}px system-ui, sans-serif`;
    ctx.textBaseline = "top";
    ctx.textAlign = "left"; /* uPlot leaves its axis alignment behind */
    for (const m of marks) {
      const px = u.valToPos(m.x, "x", true);
      if (!Number.isFinite(px) || px < left - 1 || px > left + width + 1) continue;
      ctx.strokeStyle = ctx.fillStyle = m.color || "#333";
      if (m.type === "vline") {
        ctx.lineWidth = 1.5 * dpr;
        ctx.setLineDash((m.dash || [5, 4]).map((d) => d * dpr));
        ctx.beginPath();
        ctx.moveTo(px, top);
        ctx.lineTo(px, top + height);
        ctx.stroke();
        ctx.setLineDash([]);
        if (m.label) {
          const w = ctx.measureText(m.label).width;
          const tx = px + 4 * dpr + w > left + width ? px - 4 * dpr - w : px + 4 * dpr;
          ctx.fillText(m.label, tx, top + (m.row || 0) * 16 * dpr + 4 * dpr);
        }
      } else if (m.type === "point") {
        const py = u.valToPos(m.y, "y", true);
        if (!Number.isFinite(py)) continue;
        ctx.beginPath();
        ctx.arc(px, py, 5 * dpr, 0, 2 * Math.PI);
        ctx.lineWidth = 2 * dpr;
        ctx.stroke();
        if (m.label) {
          const w = ctx.measureText(m.label).width;
          const tx = px + 8 * dpr + w > left + width ? px - 8 * dpr - w : px + 8 * dpr;
          ctx.fillText(m.label, tx, py - 18 * dpr);
        }
      }
    }
    ctx.restore();
  }

  /* Error bars (± err) on the series drawn as points (numerical results, sweeps, measured bins). */
  function drawErrorBars(u, fig, k = 1) {
    const ctx = u.ctx;
    const dpr = (devicePixelRatio || 1) * k;
    ctx.save();
    fig.series.forEach((s, si) => {
      if (!s.points || !s.err || (u.series[si + 1] && u.series[si + 1].show === false)) return;
      ctx.strokeStyle = s.color || "#333";
      ctx.lineWidth = 1.2 * dpr;
      s.x.forEach((x, i) => {
        const y = s.y[i];
        const e = s.err[i];
        if (!Number.isFinite(y) || !Number.isFinite(e) || !(e > 0)) return;
        const px = u.valToPos(x, "x", true);
        const lo = u.valToPos(fig.yLog ? Math.max(y - e, y * 1e-3) : y - e, "y", true);
        const hi = u.valToPos(y + e, "y", true);
        if (![px, lo, hi].every(Number.isFinite) || Math.abs(lo - hi) < 2 * dpr) return;
        ctx.beginPath();
        ctx.moveTo(px, lo);
        ctx.lineTo(px, hi);
        ctx.moveTo(px - 3 * dpr, lo);
        ctx.lineTo(px + 3 * dpr, lo);
        ctx.moveTo(px - 3 * dpr, hi);
        ctx.lineTo(px + 3 * dpr, hi);
        ctx.stroke();
      });
    });
    ctx.restore();
  }

  /* The y range: data range with margins, optionally clamped (fig.yClamp = [lo, hi]). */
  function yRange(fig) {
    return (u, lo, hi) => {
      if (fig.yLog) {
        return [Math.pow(10, Math.floor(Math.log10(lo))), Math.pow(10, Math.ceil(Math.log10(hi)))];
      }
      if (fig.yClamp) {
        lo = Math.max(lo, fig.yClamp[0]);
        hi = Math.min(hi, fig.yClamp[1]);
      }
      if (fig.yZero) lo = Math.min(lo, 0);
      const pad = (hi - lo) * 0.06 || 1;
      return [lo - (fig.yZero && lo === 0 ? 0 : pad), hi + pad];
    };
  }

  /* Log axes: ticks and grid at powers of ten only (every second or third one on long ranges). */
  function decades(u, axis, lo, hi) {
    const a = Math.floor(Math.log10(lo) + 1e-9);
    const b = Math.ceil(Math.log10(hi) - 1e-9);
    const step = Math.max(1, Math.ceil((b - a) / 8));
    const out = [];
    for (let e = a; e <= b; e += step) {
      const v = Math.pow(10, e);
      if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) out.push(v);
    }
    return out;
  }

  function tickLabels(log) {
    return (u, splits) =>
      splits.map((v) => {
        if (v === null) return "";
        if (log) {
          const e = Math.round(Math.log10(v));
          return e >= -2 && e <= 3 ? String(Number(Math.pow(10, e).toPrecision(1))) : `1e${e}`;
        }
        return fmt(v, 4).replace(/\.?0+e/, "e"); /* 2e+10, not 2.000e+10 */
      });
  }

  function axis(label, log, extra, k = 1) {
    const a = { label, labelSize: 18 * k, stroke: "#333", grid: { stroke: "#eee", width: k }, ticks: { width: k, size: 10 * k }, values: tickLabels(log) };
    if (k !== 1) Object.assign(a, { font: `${12 * k}px system-ui, sans-serif`, labelFont: `bold ${12 * k}px system-ui, sans-serif`, gap: 5 * k, size: 50 * k });
    if (log) a.splits = decades;
    return Object.assign(a, extra);
  }

  /* k: the scale of everything drawn (2 for the PNG's chart, drawn twice as large) */
  function options(fig, width, k = 1) {
    const series = [
      { label: fig.xName || fig.xLabel, value: (u, v) => fmt(v) },
    ];
    for (const s of fig.series) {
      const o = {
        label: s.name,
        stroke: s.color,
        width: (s.width === undefined ? 2 : s.width) * k,
        spanGaps: !s.fill,
        points: { show: !!s.points, size: 6 * k, fill: s.color },
        value: (u, v) => fmt(v),
      };
      if (s.dash) o.dash = s.dash.map((d) => d * k);
      if (s.fill) {
        o.fill = s.fill;
        o.fillTo = 0;
      }
      series.push(o);
    }
    return {
      width,
      height: HEIGHT * k,
      series,
      scales: {
        x: fig.xRange
          ? { time: false, distr: fig.xLog ? 3 : 1, log: 10, range: () => fig.xRange }
          : { time: false, distr: fig.xLog ? 3 : 1, log: 10 },
        y: { distr: fig.yLog ? 3 : 1, log: 10, range: yRange(fig) },
      },
      axes: [axis(fig.xLabel, fig.xLog, {}, k), axis(fig.yLabel, fig.yLog, { size: 64 * k }, k)],
      /* fig.bands: [{hi, lo, fill}], the area between two of fig.series (indices) filled */
      bands: (fig.bands || []).map((b) => ({ series: [b.hi + 1, b.lo + 1], fill: b.fill })),
      legend: { live: true, show: k === 1 },
      cursor: { drag: { x: true, y: false }, show: k === 1 },
      hooks: { draw: [(u) => drawErrorBars(u, fig, k), (u) => drawMarks(u, fig.marks || [], k)] },
    };
  }

  /* Draw fig into el, replacing what was there. */
  function draw(el, fig) {
    clear(el);
    const tables = fig.series.map((s) => [s.x, s.y]);
    const data = uPlot.join(tables);
    const width = Math.max(300, el.clientWidth || 600);
    const u = new uPlot(options(fig, width), data, el);
    const ro = new ResizeObserver(() => {
      const w = Math.max(300, el.clientWidth);
      if (Math.abs(w - u.width) > 2) u.setSize({ width: w, height: HEIGHT });
    });
    ro.observe(el);
    charts.set(el, { u, fig, ro });
    return u;
  }

  function clear(el) {
    const c = charts.get(el);
    if (c) {
      c.ro.disconnect();
      c.u.destroy();
      charts.delete(el);
    }
    el.replaceChildren();
  }

  function figure(el) {
    const c = charts.get(el);
    return c ? c.fig : null;
  }

  /* PNG of the chart in el: white background, title, the plot canvas, a legend line. */
  async function toPNG(el, params) {
    const c = charts.get(el);
    if (!c) return null;
    /* at least 2 pixels per CSS pixel: the chart drawn again at that ratio when the screen's is lower */
    let src = c.u.ctx.canvas;
    let dpr = devicePixelRatio || 1;
    let tmp = null;
    if (dpr < 2) {
      const k = 2 / dpr;
      const box = document.createElement("div");
      box.style.cssText = "position:absolute;left:-100000px;top:0;";
      document.body.append(box);
      tmp = new uPlot(options(c.fig, c.u.width * k, k), c.u.data, box);
      await new Promise((r) => setTimeout(r, 0)); /* uPlot sizes and draws in a microtask */
      src = tmp.ctx.canvas;
      dpr = 2;
      tmp.box = box;
    }
    const head = 28 * dpr;
    const lines = wrap(params || c.fig.params || "", 110);
    const foot = (24 + 16 * lines.length) * dpr;
    const out = document.createElement("canvas");
    out.width = src.width;
    out.height = src.height + head + foot;
    const ctx = out.getContext("2d");
    ctx.fillStyle = "#fff";
    ctx.fillRect(0, 0, out.width, out.height);
    ctx.fillStyle = "#111";
    ctx.font = `bold ${14 * dpr}px system-ui, sans-serif`;
    ctx.textBaseline = "middle";
    ctx.fillText(c.fig.title || "", 8 * dpr, head / 2);
    ctx.drawImage(src, 0, head);
    ctx.font = `${12 * dpr}px system-ui, sans-serif`;
    let x = 8 * dpr;
    const y = head + src.height + foot / 2;
    for (const s of c.fig.series) {
      ctx.fillStyle = s.color || "#333";
      ctx.fillRect(x, y - 2 * dpr, 16 * dpr, 4 * dpr);
      x += 20 * dpr;
      ctx.fillStyle = "#111";
      ctx.fillText(s.name, x, y);
      x += ctx.measureText(s.name).width + 14 * dpr;
    }
    /* the parameters it was computed for, under the legend */
    ctx.fillStyle = "#444";
    lines.forEach((l, i) => ctx.fillText(l, 8 * dpr, y + (16 + 16 * i) * dpr));
    if (tmp) {
      tmp.destroy();
      tmp.box.remove();
    }
    return new Promise((resolve) => out.toBlob(resolve, "image/png"));
  }

  /* text cut into lines of at most n characters, at spaces */
  function wrap(text, n) {
    const out = [];
    let line = "";
    for (const w of String(text).split(" ")) {
      if (line && line.length + 1 + w.length > n) out.push(line), (line = w);
      else line = line ? `${line} ${w}` : w;
    }
    if (line) out.push(line);
    return out;
  }

  /* Whether the plot canvas of el has any non-transparent pixel inside the plotting area. */
  function inked(el) {
    const c = charts.get(el);
    if (!c) return 0;
    const { left, top, width, height } = c.u.bbox;
    const img = c.u.ctx.getImageData(left, top, Math.max(1, width), Math.max(1, height)).data;
    let n = 0;
    for (let i = 3; i < img.length; i += 4) if (img[i] !== 0) n++;
    return n;
  }

  return { draw, clear, figure, toPNG, inked, fmt, errFmt };
})();

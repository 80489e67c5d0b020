/* topo.js -- a measured topography on the page (issue 15): upload a height matrix (text), see
 * its isotropic PSD on log axes with the power-law fit, pick k1 and k2 on the plot, and compute
 * the adhesion of that part of the spectrum.
 *
 * The file goes as it is to POST /v1/psd?dx=…&dy=…&periodic=… (Content-Type text/plain; the
 * material's fields too when the form has one), so the server parses it (up to 64 MiB) and
 * answers problems with the pointer of the JSON request: /topography/heights/ROW/COL (line
 * and column in the detail) shows beside the file field, /topography/dx beside dx. The answer is
 * in SI (k in 1/m, P in m⁴, the project's convention 2π∫kP dk = h_rms²). Adhesion: the bins
 * between k1 and k2 (log-log interpolated at both ends) as a table PSD, with the fitted power
 * law as its tail when k2 is empty (∞), sent with the form's material and "units":"SI"; the
 * server checks k1 > k̃0/χ and says so beside k1 otherwise.
 */
"use strict";

const LJTopo = (() => {
  const $ = (id) => document.getElementById(id);
  let api = null; /* app.js's helpers */
  let psd = null; /* the last 200 answer of /v1/psd */
  let chart = null; /* its uPlot */

  /* The query of the text upload: dx, dy, periodic and the material, as the form has them. */
  function query() {
    const q = new URLSearchParams();
    q.set("dx", $("topo-dx").value.trim());
    if ($("topo-dy").value.trim() !== "") q.set("dy", $("topo-dy").value.trim());
    if ($("topo-periodic").checked) q.set("periodic", "true");
    const m = api.materialObject();
    for (const [k, v] of Object.entries(m || {})) if (v !== undefined && v !== null) q.set(k, String(v));
    return q.toString();
  }

  /* The power law of the fit over the band binned. */
  function fitLine(a) {
    if (!a.fit) return null;
    const k = [a.k[0], a.k[a.k.length - 1]];
    return { k, P: k.map((x) => a.fit.C * Math.pow(x, 2 * a.fit.D - 8)) };
  }

  const kOf = (id) => {
    const v = api.val($(id).value);
    return typeof v === "number" ? v : null;
  };

  function draw() {
    const a = psd;
    const p = api.panels.topo;
    const series = [{ name: "P (bins, m⁴)", x: a.k, y: a.P, err: a.error.P, color: "#1f5fbf", points: true }];
    const f = fitLine(a);
    if (f) series.push({ name: `fit: D = ${api.fmt(a.fit.D, 4)} ± ${api.errFmt(a.error.fit.D)}`, x: f.k, y: f.P, color: "#d1495b", dash: [6, 4] });
    const marks = [];
    const k1 = kOf("topo-k1");
    const k2 = kOf("topo-k2");
    if (k1 !== null) marks.push({ type: "vline", x: k1, label: "k1", color: "#2e933c" });
    if (k2 !== null) marks.push({ type: "vline", x: k2, label: "k2", color: "#2e933c" });
    if (a.domain) marks.push({ type: "vline", x: a.domain.k0, label: "k0/χ", color: "#d1495b", dash: [2, 3], row: 1 });
    const xs = a.k.concat(a.domain ? [a.domain.k0] : []);
    chart = api.showSeries("topo", series, {
      xLabel: "k (1/m)", xName: "k", yLabel: "P (m⁴)", xLog: true, yLog: true,
      xRange: [Math.min(...xs) / 1.5, Math.max(...xs) * 1.5], marks,
    }, p.answers);
    /* a click on the plot sets k1 or k2 (the selector says which) */
    chart.over.addEventListener("click", (e) => {
      const k = chart.posToVal(e.offsetX, "x");
      if (!(k > 0)) return;
      $(`topo-${$("topo-pick").value}`).value = Number(k.toPrecision(4)).toString();
      draw();
    });
  }

  function readout(a) {
    const e = a.error;
    const t = api.el("table", {});
    const row = (name, v, err, unit) => t.append(api.el("tr", {}, api.el("th", {}, name), api.el("td", {}, `${api.fmt(v, 5)}${unit ? ` ${unit}` : ""}`), api.el("td", {}, err === undefined ? "" : `± ${api.errFmt(err)}`)));
    row("h_rms", a.h_rms, e.h_rms, "m");
    row("rms slope", a.rms_slope, e.rms_slope);
    if (a.fit) {
      row("D (H = 3 − D)", a.fit.D, e.fit.D);
      row("C", a.fit.C, e.fit.C, `m^${api.fmt(2 * a.fit.D - 4, 3)}`);
      row("fit band", a.fit.k_min, undefined, `… ${api.fmt(a.fit.k_max, 4)} 1/m (${a.fit.bins} bins)`);
    }
    const g = a.grid;
    const notes = [`${g.nx} × ${g.ny} heights, ${g.periodic ? "periodic (mean removed, no window)" : `${g.detrend} removed, Hann window`}; bins ${api.fmt(a.k[0], 4)} … ${api.fmt(a.k[a.k.length - 1], 4)} 1/m`];
    if (a.domain) notes.push(`theory's domain k > k0/χ = ${api.fmt(a.domain.k0, 4)} 1/m: ${a.domain.inside} of the band; proposed k1 = ${api.fmt(a.domain.k1, 4)} 1/m (k̃1 = ${api.fmt(a.domain.k1_dimensionless, 4)})`);
    else notes.push("give a material above to see the theory's domain and compute the adhesion");
    $("readout-topo").replaceChildren(t, ...notes.map((n) => api.el("div", { class: "meta" }, n)), api.metaLine(a), ...api.warnings(a));
  }

  /* The height map was answered with a problem: beside the fields, and in the readout. */
  function refused(status, json) {
    psd = null;
    const loose = api.placeProblem(json, "topo");
    $("readout-topo").replaceChildren(api.el("div", { class: "problem" }, `${status} ${json.title || ""}: ${json.detail || ""}`), ...loose.map((t) => api.el("div", { class: "problem" }, t)));
    api.setIdle("The height map was refused: see the highlighted fields.", true);
  }

  async function computePsd() {
    const f = $("topo-file").files[0];
    api.clearErrors();
    if (!f) {
      api.showFieldError("topo-file", "choose a file: a matrix of heights in m, one row a line");
      return;
    }
    const text = await f.text();
    const q = query();
    const p = api.resetPanel("topo");
    /* the export records the upload (its file and query), not the matrix itself */
    p.requests.push({ endpoint: `psd?${q}`, text: JSON.stringify({ file: f.name, bytes: text.length, content_type: "text/plain", query: q }), label: "psd" });
    $("card-topo").hidden = false;
    api.setBusy(`psd of ${f.name}`);
    let res;
    try {
      res = await api.post("psd", text, undefined, { contentType: "text/plain", query: q });
    } catch (e) {
      api.setIdle(`Request failed: ${e.message}`, true);
      return;
    }
    p.answers.push(res.json);
    if (res.status !== 200) {
      refused(res.status, res.json || {});
      return;
    }
    psd = res.json;
    $("topo-k1").value = api.fmt(psd.domain ? psd.domain.k1 : psd.k[0], 6);
    $("topo-k2").value = "";
    readout(psd);
    draw();
    $("readout-topo-adhesion").textContent = "Pick k1 and k2 (empty: ∞) and compute the adhesion of the spectrum between them.";
    api.setIdle(`PSD of ${f.name}: ${psd.k.length} bins.`);
  }

  /* log-log interpolation of the bins at k (inside them) */
  function at(a, k) {
    let i = 0;
    while (i + 2 < a.k.length && a.k[i + 1] < k) i++;
    const t = Math.log(k / a.k[i]) / Math.log(a.k[i + 1] / a.k[i]);
    return Math.exp(Math.log(a.P[i]) + t * Math.log(a.P[i + 1] / a.P[i]));
  }

  /* The table PSD of the bins in [k1, k2] (k2 null: to the end, then the fitted tail). */
  function spectrum(a, k1, k2) {
    const k = [];
    const P = [];
    const last = a.k[a.k.length - 1];
    if (k1 > a.k[0] && k1 < last) k.push(k1), P.push(at(a, k1));
    a.k.forEach((x, i) => {
      if (x >= k1 && (k2 === null || x <= k2)) k.push(x), P.push(a.P[i]);
    });
    if (k2 !== null && k2 > a.k[0] && k2 < last && k[k.length - 1] < k2) k.push(k2), P.push(at(a, k2));
    const out = { kind: "table", k, P };
    if (k2 === null && a.fit && 2 * a.fit.D - 8 < -2) out.tail = { exponent: 2 * a.fit.D - 8 };
    return out;
  }

  async function computeAdhesion() {
    if (!psd) return;
    api.clearErrors();
    const m = api.materialObject();
    if (!m) {
      $("readout-topo-adhesion").textContent = "Give the material (SI) above: the spectrum is in SI and the theory needs its scales χ and σ0.";
      return;
    }
    const k1 = kOf("topo-k1");
    const k2 = kOf("topo-k2");
    if (k1 === null) {
      api.showFieldError("topo-k1", "k1 must be a number (1/m)");
      return;
    }
    const body = { psd: spectrum(psd, k1, k2), material: m, units: "SI" };
    const text = JSON.stringify(body);
    const p = api.panels.topo;
    p.requests.push({ endpoint: "adhesion", text, label: "adhesion" });
    api.setBusy("adhesion of the measured spectrum");
    let res;
    try {
      res = await api.post("adhesion", text);
    } catch (e) {
      api.setIdle(`Request failed: ${e.message}`, true);
      return;
    }
    p.answers.push(res.json);
    const ro = $("readout-topo-adhesion");
    if (res.status !== 200) {
      const loose = api.placeProblem(res.json || {}, "topo-adhesion");
      ro.replaceChildren(api.el("div", { class: "problem" }, `${res.status} ${res.json.title || ""}: ${res.json.detail || ""}`), ...loose.map((t) => api.el("div", { class: "problem" }, t)));
      api.setIdle("The spectrum was refused: see k1 and k2.", true);
      return;
    }
    const a = res.json;
    ro.replaceChildren(
      api.el("div", { class: "meta" }, `${body.psd.k.length} points from k1 = ${api.fmt(k1, 4)} to ${k2 === null ? "∞ (fitted tail)" : `k2 = ${api.fmt(k2, 4)}`} 1/m`),
      api.summaryTable(a, a.error, a.si, a.si && a.si.error),
      api.metaLine(a),
      ...api.warnings(a)
    );
    api.setIdle(`Adhesion of the measured spectrum: Δγeff/Δγ = ${api.fmt(a.dgamma_eff, 4)}.`);
  }

  function init(helpers) {
    api = helpers;
    $("topo-compute").addEventListener("click", computePsd);
    $("topo-adhesion").addEventListener("click", computeAdhesion);
    for (const id of ["topo-k1", "topo-k2"]) $(id).addEventListener("change", () => psd && draw());
  }

  return { init, spectrum, query, refused };
})();

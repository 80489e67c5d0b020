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
 *
 * Several files (one surface measured at several scales, issue 25): each gets its own dx in a
 * small table, goes to /v1/psd on its own (without the material: the whole measured band), and
 * their psd objects (the answer's own when it has P_err, else its bins within its fit's band
 * with error.P, as `ljgap combine` takes them) go to POST /v1/psd/combine. The plot shows each
 * measurement's bins, the combination with its error band (P ± P_err) and its fit; the
 * combination is what k1, k2 and the adhesion then use, and "Combined PSD as CSV" exports it.
 *
 * "Use this spectrum" (issue 30): the psd object between k1 and k2 (one map's or the
 * combination's, P_err and tail kept) goes with the material into the page's calculation
 * (LJApp's useSpectrum): traction, PDF and, with a radius, the pull-off, in SI. An empty or
 * binary file is refused here in one line; a refused map empties the card. The card says what
 * it was "computed for" (files, dx, dy, periodic, detrend, material) and marks that line once
 * one of those inputs changes.
 *
 * An instrument's own file (issue 28: NanoScope, .gwy, .gsf, xyz columns, X3P, … chosen or
 * dropped on the card) goes as application/octet-stream with the same query but dx and dy, which
 * the file gives (sent only when the server says the file states no size); the server recognises
 * the format. Its answer's source fills a channel selector (a change sends the file again with
 * channel=) and the readout says what the file said: format, channel, instrument, date, size,
 * unit and the missing points (the PSD is that of their largest complete rectangle).
 */
"use strict";

const LJTopo = (() => {
  const $ = (id) => document.getElementById(id);
  let api = null; /* app.js's helpers */
  let psd = null; /* the last 200 answer of /v1/psd */
  let chart = null; /* its uPlot */
  let measured = []; /* several files: [{name, answer}] of /v1/psd, psd the combination */
  const COLORS = ["#1f5fbf", "#2e933c", "#8e44ad", "#e67e22", "#16a085", "#7f8c8d", "#c0392b", "#2c3e50"];

  /* An instrument's file, not a text matrix: by its extension, a binary start or a format's
   * text magic. */
  const INSTRUMENT_EXT = /\.(spm|000|001|002|003|di|gwy|gsf|xyz|x3p|sur|nc|ibw|tiff?|plu)$/i;
  async function isInstrument(f) {
    if (INSTRUMENT_EXT.test(f.name)) return true;
    const b = new Uint8Array(await f.slice(0, 4096).arrayBuffer());
    const head = new TextDecoder("latin1").decode(b.slice(0, 32));
    return b.includes(0) || head.startsWith("\\*File list") || head.startsWith("Gwyddion Simple Field");
  }

  /* The query of an instrument file: what the text upload's has but dx, dy (given only when
   * withDx: the file states no size), and the channel chosen. */
  function fileQuery(withDx, material) {
    const q = new URLSearchParams(query(undefined, material));
    if (!withDx) q.delete("dx"), q.delete("dy");
    const ch = $("topo-channel");
    if (ch && !ch.hidden && ch.value !== "") q.set("channel", ch.value);
    return q.toString();
  }

  /* The channel selector from an answer's source (hidden with one channel or none). */
  function channels(source) {
    const sel = $("topo-channel");
    const box = $("topo-channel-field");
    if (!sel || !box) return;
    const list = source ? source.channels : [];
    box.hidden = list.length < 2;
    sel.replaceChildren(...list.map((t, i) => api.el("option", { value: String(i) }, `${i}: ${t}`)));
    if (source) sel.value = String(Math.max(0, list.indexOf(source.channel)));
  }

  /* What the file said (an answer's source), one line for the readout. */
  function sourceLine(s) {
    const size = s.size ? `${api.fmt(s.size[0], 4)} × ${api.fmt(s.size[1], 4)} m` : "no size stated";
    const parts = [`file: ${s.format}, channel "${s.channel}"${s.channels.length > 1 ? ` of ${s.channels.length}` : ""}`,
      `${s.nx} × ${s.ny} points, ${size}`, `heights in ${s.z_unit || "m (no unit stated)"}`];
    if (s.instrument) parts.push(`instrument ${s.instrument}`);
    if (s.acquired) parts.push(`acquired ${s.acquired}`);
    if (s.tip_radius) parts.push(`tip radius ${api.fmt(s.tip_radius, 3)} m`);
    const u = s.missing.used;
    parts.push(s.missing.count ? `${s.missing.count} points missing: the PSD is that of the largest complete rectangle, ${u.nx} × ${u.ny} from column ${u.x0}, row ${u.y0}` : "no point missing");
    return parts.join("; ");
  }

  /* The query of the text upload: dx, dy, periodic and the material, as the form has them. */
  function query(dx, material) {
    const q = new URLSearchParams();
    q.set("dx", dx === undefined ? $("topo-dx").value.trim() : dx);
    if (dx === undefined && $("topo-dy").value.trim() !== "") q.set("dy", $("topo-dy").value.trim());
    if ($("topo-periodic").checked) q.set("periodic", "true");
    const m = dx === undefined || material ? api.materialObject() : null; /* several maps: the whole band */
    for (const [k, v] of Object.entries(m || {})) if (v !== undefined && v !== null) q.set(k, String(v));
    return q.toString();
  }

  /* The inputs of the card as one line (its "computed for"): the file(s) with their dx, dy,
   * periodic and, for one map, the material. */
  function inputsLine() {
    const files = [...$("topo-file").files];
    const parts = [];
    if (files.length > 1) {
      parts.push(files.map((f, i) => `${f.name} (dx = ${$(`topo-dx-${i}`) ? $(`topo-dx-${i}`).value.trim() : $("topo-dx").value.trim()} m)`).join(", "));
    } else {
      parts.push(files.length ? files[0].name : "no file");
      const ch = $("topo-channel");
      if (ch && !$("topo-channel-field").hidden) parts.push(`channel ${ch.value}`);
      parts.push(`dx = ${$("topo-dx").value.trim()} m`);
      parts.push(`dy = ${$("topo-dy").value.trim() === "" ? "dx" : `${$("topo-dy").value.trim()} m`}`);
    }
    parts.push($("topo-periodic").checked ? "periodic" : "not periodic");
    const m = api.materialObject();
    parts.push(m ? `material ${Object.entries(m).map(([k, v]) => `${k} = ${v}`).join(", ")}` : "no material");
    return parts.join("; ");
  }

  let computedFor = null; /* inputsLine() of the card's result, null when it has none */
  /* The card's "computed for" line; when the inputs have changed since, it says so. */
  function markStale() {
    const line = $("topo-for");
    if (!line) return;
    const stale = computedFor !== null && inputsLine() !== computedFor;
    line.classList.toggle("stale", stale);
    line.textContent = computedFor === null ? "" : `computed for: ${computedFor}${computedHow ? `; ${computedHow}` : ""}${stale ? " — the inputs above have changed since: Compute PSD again" : ""}`;
  }
  let computedHow = ""; /* the server's treatment of the map (detrend, window) */
  function forLine(detrend) {
    computedFor = inputsLine();
    computedHow = detrend || "";
    api.panels.topo.params = `${computedFor}${detrend ? `; ${detrend}` : ""}`;
    return api.el("div", { class: "meta computed-for", id: "topo-for" });
  }

  /* Several files: a dx field for each (the card's dx to start with). */
  function listFiles() {
    const files = [...$("topo-file").files];
    const box = $("topo-files");
    box.hidden = files.length < 2;
    if (files.length < 2) return box.replaceChildren();
    const rows = files.map((f, i) =>
      api.el("label", { class: "topo-file-dx" }, `dx of ${f.name} (m) `,
        api.el("input", { id: `topo-dx-${i}`, class: "short", type: "text", inputmode: "decimal", value: $("topo-dx").value.trim() })));
    box.replaceChildren(api.el("div", { class: "meta" }, `${files.length} measurements of one surface: one PSD of all (dy = dx for each; the material is not used for them)`), ...rows);
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
    if (measured.length) return drawCombined();
    const a = psd;
    const p = api.panels.topo;
    const series = [{ name: "P (bins, m⁴)", x: a.k, y: a.P, err: a.error.P, color: "#1f5fbf", points: true }];
    const f = fitLine(a);
    if (f) series.push({ name: `fit: D = ${api.fmt(a.fit.D, 4)} ± ${api.errFmt(a.error.fit.D)}`, x: f.k, y: f.P, color: "#d1495b", dash: [6, 4] });
    const marks = a.domain ? [{ type: "vline", x: a.domain.k0, label: "k0/χ", color: "#d1495b", dash: [2, 3], row: 1 }] : [];
    marks.push(...bands(a));
    plot(series, a.k.concat(a.domain ? [a.domain.k0] : []), marks, p.answers);
  }

  /* The fit band and the reliable band of an answer, as marks on the plot. */
  function bands(a) {
    const out = [];
    if (a.reliable && a.reliable.k_min) {
      out.push({ type: "vline", x: a.reliable.k_min, label: "reliable from", color: "#8e44ad", dash: [1, 3], row: 2 });
      out.push({ type: "vline", x: a.reliable.k_max, label: "reliable to", color: "#8e44ad", dash: [1, 3], row: 2 });
    }
    if (a.fit && a.fit.k_min) {
      out.push({ type: "vline", x: a.fit.k_min, label: "fit band", color: "#e67e22", dash: [4, 2], row: 3 });
      out.push({ type: "vline", x: a.fit.k_max, label: "fit band", color: "#e67e22", dash: [4, 2], row: 3 });
    }
    return out;
  }

  /* The panel's log-log chart of series over the k in xs, with marks and k1, k2; a click on it
   * sets k1 or k2 (the selector says which). */
  function plot(series, xs, marks, answers) {
    const k1 = kOf("topo-k1");
    const k2 = kOf("topo-k2");
    if (k1 !== null) marks.push({ type: "vline", x: k1, label: "k1", color: "#2e933c" });
    if (k2 !== null) marks.push({ type: "vline", x: k2, label: "k2", color: "#2e933c" });
    chart = api.showSeries("topo", series, {
      xLabel: "k (1/m)", xName: "k", yLabel: "P (m⁴)", xLog: true, yLog: true,
      xRange: [Math.min(...xs) / 1.5, Math.max(...xs) * 1.5], marks,
    }, answers);
    chart.over.addEventListener("click", (e) => {
      const k = chart.posToVal(e.offsetX, "x");
      if (!(k > 0)) return;
      $(`topo-${$("topo-pick").value}`).value = Number(k.toPrecision(4)).toString();
      draw();
    });
  }

  function readout(a) {
    const e = a.error;
    const t = api.el("table", {}, api.el("tr", {}, ...["quantity", "value (SI)", "± err"].map((h) => api.el("th", {}, h))));
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
    if (a.source) notes.unshift(sourceLine(a.source));
    $("readout-topo").replaceChildren(t, ...notes.map((n) => api.el("div", { class: "meta" }, n)), forLine(g.periodic ? "mean removed" : `${g.detrend} removed, Hann window`), api.metaLine(a), ...api.warnings(a));
    markStale();
  }

  /* The height map was answered with a problem: beside the fields, and in the readout. */
  function refused(status, json) {
    psd = null;
    measured = [];
    computedFor = null;
    /* nothing of the map before stays on the card */
    api.emptyPanel("topo");
    $("topo-k1").value = "";
    $("topo-k2").value = "";
    $("readout-topo-adhesion").replaceChildren();
    $("topo-combined").hidden = true;
    api.updateExports();
    const loose = api.placeProblem(json, "topo");
    $("readout-topo").replaceChildren(api.el("div", { class: "problem" }, `${status} ${json.title || ""}: ${json.detail || ""}`), ...loose.map((t) => api.el("div", { class: "problem" }, t)));
    api.focusFirstInvalid();
    api.setIdle("The height map was refused: see the highlighted fields.", true);
  }

  /* A file that cannot be a height map as text (empty, or binary: an image, a native AFM
   * format): one line, before anything is sent. null when it may be one. */
  async function notText(f) {
    if (f.size === 0) return `not a height map: ${f.name} is empty`;
    const b = new Uint8Array(await f.slice(0, 4096).arrayBuffer());
    /* images and documents; any other binary may be an instrument's file (the server says) */
    const magic = [[[0x89, 0x50, 0x4e, 0x47], "a PNG image"], [[0xff, 0xd8, 0xff], "a JPEG image"], [[0x25, 0x50, 0x44, 0x46], "a PDF"]];
    for (const [m, what] of magic) if (m.every((x, i) => b[i] === x)) return `not a height map: ${f.name} is ${what}; export the heights as text (one row a line) or send the instrument's own file`;
    return null;
  }

  async function checkFiles(files) {
    for (const f of files) {
      const why = await notText(f);
      if (why) {
        refused(422, { title: "Not a height map", detail: why, errors: [] });
        api.showFieldError("topo-file", why);
        $("readout-topo").replaceChildren(api.el("div", { class: "problem" }, why));
        api.setIdle(why, true);
        api.focusFirstInvalid();
        return false;
      }
    }
    return true;
  }

  /* POSTs text to endpoint (opts as api.post takes them) and records the answer in panel p:
   * the 200 answer, or null after showing why (who, when given, starts a problem's detail). */
  async function ask(p, endpoint, text, opts, who) {
    let res;
    try {
      res = await api.post(endpoint, text, undefined, opts);
    } catch (e) {
      api.setIdle(`Request failed: ${e.message}`, true);
      return null;
    }
    p.answers.push(res.json);
    if (res.status === 200) return res.json;
    const j = res.json || {};
    refused(res.status, who ? { ...j, detail: `${who}: ${j.detail || ""}` } : j);
    return null;
  }

  /* One height map f to /v1/psd as text with the query q (ask's answer); the export records
   * the upload (its file and query), not the matrix itself. */
  async function upload(p, f, q, label, who) {
    if (await isInstrument(f)) return uploadFile(p, f, q, label, who);
    const text = await f.text();
    p.requests.push({ endpoint: `psd?${q}`, text: JSON.stringify({ file: f.name, bytes: text.length, content_type: "text/plain", query: q }), label });
    return ask(p, "psd", text, { contentType: "text/plain", query: q }, who);
  }

  /* An instrument file f to /v1/psd as application/octet-stream: first without dx (the file
   * gives it), again with the form's dx when the server says the file states no size. */
  async function uploadFile(p, f, q, label, who) {
    const material = !!new URLSearchParams(q).get("dgamma");
    for (const withDx of [false, true]) {
      const fq = fileQuery(withDx, material);
      p.requests.push({ endpoint: `psd?${fq}`, text: JSON.stringify({ file: f.name, bytes: f.size, content_type: "application/octet-stream", query: fq }), label });
      let res;
      try {
        res = await api.post("psd", f, undefined, { contentType: "application/octet-stream", query: fq });
      } catch (e) {
        api.setIdle(`Request failed: ${e.message}`, true);
        return null;
      }
      const j = res.json || {};
      const noSize = res.status === 422 && (j.errors || []).some((e) => e.pointer === "/topography/dx" && /does not state its physical size/.test(e.detail));
      if (noSize && !withDx) continue;
      p.answers.push(j);
      if (res.status === 200) {
        channels(j.source);
        return j;
      }
      refused(res.status, who ? { ...j, detail: `${who}: ${j.detail || ""}` } : j);
      return null;
    }
    return null;
  }

  async function computePsd() {
    const f = $("topo-file").files[0];
    api.clearErrors();
    if (!f) {
      api.showFieldError("topo-file", "choose a file: a matrix of heights in m, one row a line");
      return;
    }
    $("card-topo").hidden = false;
    if (!(await checkFiles([...$("topo-file").files]))) return;
    if ($("topo-file").files.length > 1) return computeCombined([...$("topo-file").files]);
    measured = [];
    $("topo-combined").hidden = true;
    fresh();
    const p = api.panels.topo;
    $("card-topo").hidden = false;
    api.setBusy(`psd of ${f.name}`);
    const a = await upload(p, f, query(), "psd");
    if (!a) return;
    psd = a;
    $("topo-k1").value = api.fmt(psd.domain ? psd.domain.k1 : psd.k[0], 6);
    $("topo-k2").value = "";
    readout(psd);
    draw();
    $("readout-topo-adhesion").textContent = "Pick k1 and k2 (empty: ∞) and compute the adhesion of the spectrum between them.";
    api.updateExports();
    api.setIdle(`PSD of ${f.name}: ${psd.k.length} bins.`);
  }

  /* The psd object of a /v1/psd answer for the combination (as ljgap__combine_body makes it). */
  /* The psd object of a /v1/psd answer, for the combine: null when it has none (or no P_err). */
  function psdObject(a) {
    return a.psd && a.psd.kind === "table" && a.psd.P_err ? a.psd : null;
  }

  function drawCombined() {
    const c = psd;
    const series = measured.map((m, i) => ({ name: `${m.name} (bins, m⁴)`, x: m.answer.k, y: m.answer.P, err: m.answer.error.P, color: COLORS[i % COLORS.length], points: true }));
    series.push({ name: "combined P (m⁴)", x: c.k, y: c.P, err: c.error.P, color: "#111" });
    series.push({ name: "combined P + P_err", x: c.k, y: c.P.map((p, i) => p + c.error.P[i]), color: "#999", dash: [3, 3] });
    series.push({ name: "combined P − P_err", x: c.k, y: c.P.map((p, i) => (p > c.error.P[i] ? p - c.error.P[i] : null)), color: "#999", dash: [3, 3] });
    const f = fitLine(c);
    if (f) series.push({ name: `fit: D = ${api.fmt(c.fit.D, 4)} ± ${api.errFmt(c.error.fit.D)}`, x: f.k, y: f.P, color: "#d1495b", dash: [6, 4] });
    const marks = c.gaps.map((g) => ({ type: "vline", x: Math.sqrt(g.k_min * g.k_max), label: "gap", color: "#d1495b", dash: [2, 3], row: 1 }));
    marks.push(...bands(c));
    plot(series, measured.flatMap((m) => [m.answer.k[0], m.answer.k[m.answer.k.length - 1]]), marks, api.panels.topo.answers);
  }

  function readoutCombined(c) {
    const t = api.el("table", {}, api.el("tr", {}, ...["quantity", "value (SI)", "± err"].map((h) => api.el("th", {}, h))));
    const row = (name, v, err, unit) => t.append(api.el("tr", {}, api.el("th", {}, name), api.el("td", {}, `${api.fmt(v, 5)}${unit ? ` ${unit}` : ""}`), api.el("td", {}, err === undefined ? "" : `± ${api.errFmt(err)}`)));
    if (c.fit) {
      row("D (H = 3 − D)", c.fit.D, c.error.fit.D);
      row("C", c.fit.C, c.error.fit.C, `m^${api.fmt(2 * c.fit.D - 4, 3)}`);
      row("fit band", c.fit.k_min, undefined, `… ${api.fmt(c.fit.k_max, 4)} 1/m (${c.fit.points} points, χ²_red ${api.fmt(c.fit.chi2_red, 3)})`);
    }
    const notes = measured.map((m, i) => `${m.name}: k = ${api.fmt(c.sources[i].k_min, 4)} … ${api.fmt(c.sources[i].k_max, 4)} 1/m, ${c.sources[i].points} points of the combination`);
    const ag = c.agreement;
    notes.push(ag.dof ? `overlap: χ² = ${api.fmt(ag.chi2, 3)} for ${ag.dof} degrees of freedom (p = ${api.fmt(ag.p, 2)}); ${ag.inflated} errors inflated` : "the measurements do not overlap");
    notes.push(`combined: ${c.k.length} points, ${api.fmt(c.k[0], 4)} … ${api.fmt(c.k[c.k.length - 1], 4)} 1/m; tail ${c.psd && c.psd.tail ? `k^${api.fmt(c.psd.tail.exponent, 4)} from ${c.tail_from}` : "none"}`);
    if (c.domain) {
      const d = c.domain;
      notes.push(`theory's domain k > k0/χ = ${api.fmt(d.k0, 4)} 1/m: ${d.inside} of the combined band (${api.fmt(100 * d.fraction, 3)} %); the psd object starts at k1 = ${api.fmt(d.k1, 4)} 1/m${d.h_rms === null ? "" : `, h_rms = ${api.fmt(d.h_rms, 4)} m`}`);
    }
    $("readout-topo").replaceChildren(t, ...notes.map((n) => api.el("div", { class: "meta" }, n)), forLine(), api.metaLine(c), ...api.warnings(c));
    markStale();
  }

  /* The combination as CSV with units. */
  function combinedCSV() {
    const c = psd;
    const lines = [
      `# ljgap psd/combine: ${measured.map((m) => m.name).join(", ")}`,
      `# the project's convention: k angular, 2 pi int k P dk = h_rms^2; fit D = ${c.fit ? c.fit.D : ""} +- ${c.fit ? c.error.fit.D : ""}`,
      "k [1/m],P [m^4],P_err [m^4],inputs",
    ];
    c.k.forEach((k, i) => lines.push([k, c.P[i], c.error.P[i], c.inputs[i]].join(",")));
    return lines.join("\n") + "\n";
  }

  /* A new computation: nothing of the previous result stays on the card meanwhile. */
  function fresh() {
    psd = null;
    computedFor = null;
    api.emptyPanel("topo");
    $("readout-topo").textContent = "Computing the PSD …";
    $("readout-topo-adhesion").replaceChildren();
    api.updateExports();
  }

  /* Several files: each one's PSD, then their combination. */
  async function computeCombined(files) {
    fresh();
    const p = api.panels.topo;
    measured = [];
    psd = null;
    $("card-topo").hidden = false;
    $("topo-combined").hidden = true;
    const answers = [];
    for (const [i, f] of files.entries()) {
      const dx = $(`topo-dx-${i}`) ? $(`topo-dx-${i}`).value.trim() : $("topo-dx").value.trim();
      api.setBusy(`psd of ${f.name} (${i + 1} of ${files.length})`);
      const a = await upload(p, f, query(dx), `psd ${f.name}`, f.name);
      if (!a) return;
      answers.push({ name: f.name, answer: a });
    }
    const none = answers.find((m) => !psdObject(m.answer));
    if (none) {
      api.setIdle(`${none.name}: its /v1/psd answer has no psd table with P_err (see its warnings), so it cannot be combined.`, true);
      return;
    }
    const req = { psds: answers.map((m) => psdObject(m.answer)) };
    const mat = api.materialObject();
    if (mat) req.material = mat;
    const body = JSON.stringify(req);
    p.requests.push({ endpoint: "psd/combine", text: body, label: "psd/combine" });
    api.setBusy(`combining ${files.length} PSDs`);
    const c = await ask(p, "psd/combine", body, {});
    if (!c) return;
    measured = answers;
    psd = c;
    $("topo-k1").value = api.fmt(psd.psd ? psd.psd.k[0] : psd.k[0], 6);
    $("topo-k2").value = "";
    readoutCombined(psd);
    draw();
    $("topo-combined").hidden = false;
    $("readout-topo-adhesion").textContent = "Pick k1 and k2 (empty: ∞) and compute the adhesion of the combined spectrum between them.";
    api.updateExports();
    api.setIdle(`Combined PSD of ${files.length} measurements: ${psd.k.length} points.`);
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
      /* (k1 on a bin is that bin once) */
      if (x >= k1 && (k2 === null || x <= k2) && !(k.length && x <= k[k.length - 1])) k.push(x), P.push(a.P[i]);
    });
    if (k2 !== null && k2 > a.k[0] && k2 < last && k[k.length - 1] < k2) k.push(k2), P.push(at(a, k2));
    const out = { kind: "table", k, P };
    if (k2 === null && a.fit && 2 * a.fit.D - 8 < -2) out.tail = { exponent: 2 * a.fit.D - 8 };
    return out;
  }

  /* A table psd object (k, P, P_err, tail) cut to [k1, k2] (k2 null: to its end, with its
   * tail), log-log between its knots: the combined psd object for the adhesion. */
  function cut(o, k1, k2) {
    const k = [];
    const P = [];
    const E = [];
    const at0 = []; /* each knot's index in o (-1: interpolated), for P_corr */
    const n = o.k.length;
    const atErr = (x) => {
      let i = 0;
      while (i + 2 < n && o.k[i + 1] < x) i++;
      const t = Math.log(x / o.k[i]) / Math.log(o.k[i + 1] / o.k[i]);
      const p = at(o, x);
      return p * ((1 - t) * (o.P_err[i] / o.P[i]) + t * (o.P_err[i + 1] / o.P[i + 1]));
    };
    if (k1 > o.k[0] && k1 < o.k[n - 1]) k.push(k1), P.push(at(o, k1)), E.push(atErr(k1)), at0.push(-1);
    o.k.forEach((x, i) => {
      if (x >= k1 && (k2 === null || x <= k2) && !(k.length && x <= k[k.length - 1])) k.push(x), P.push(o.P[i]), E.push(o.P_err[i]), at0.push(i);
    });
    if (k2 !== null && k2 > o.k[0] && k2 < o.k[n - 1] && k[k.length - 1] < k2) k.push(k2), P.push(at(o, k2)), E.push(atErr(k2)), at0.push(-1);
    const out = { kind: "table", k, P, P_err: E };
    /* the neighbours' correlation of the knots kept side by side (an interpolated knot: 0) */
    if (o.P_corr && k.length > 1) out.P_corr = at0.slice(1).map((j, m) => (at0[m] >= 0 && j === at0[m] + 1 ? o.P_corr[at0[m]] : 0));
    if (k2 === null && o.tail) out.tail = o.tail;
    return out;
  }

  /* The spectrum between k1 and k2 as a psd object: the server's own (with P_err and its tail)
   * cut to them, else the bins'. */
  function chosen(k1, k2) {
    if (measured.length) return cut(psd.psd, k1, k2);
    return psd.psd && psd.psd.P_err && psd.psd.k.length > 1 ? cut(psd.psd, Math.max(k1, psd.psd.k[0]), k2) : spectrum(psd, k1, k2);
  }

  /* "Use this spectrum": the chosen part of the measured PSD becomes the calculation's PSD. */
  async function useIt() {
    if (!psd) return;
    api.clearErrors();
    if (!api.materialObject()) {
      api.showFieldError("topo-k1", "give the material (SI) above first: the spectrum is in SI and the theory needs its scales χ and σ0");
      $("readout-topo-adhesion").textContent = "Give the material (SI) above: the spectrum is in SI and the theory needs its scales χ and σ0.";
      api.setIdle("Give the material first.", true);
      return;
    }
    const k1 = kOf("topo-k1");
    const k2 = kOf("topo-k2");
    if (k1 === null) {
      api.showFieldError("topo-k1", "k1 must be a number (1/m)");
      api.focusFirstInvalid();
      return;
    }
    if (measured.length && !psd.psd) {
      $("readout-topo-adhesion").textContent = "The combination has no psd object (see its warnings): nothing to use.";
      return;
    }
    const names = measured.length ? measured.map((x) => x.name).join(" + ") : ($("topo-file").files[0] || {}).name || "measured map";
    const label = `${names}, k ${api.fmt(k1, 4)} … ${k2 === null ? "∞" : api.fmt(k2, 4)} 1/m`;
    $("readout-topo-adhesion").textContent = `Used as the calculation's PSD: ${label}.`;
    await api.useSpectrum(chosen(k1, k2), label);
  }

  /* The card's CSV: the spectrum's psd object (k, P, P_err with units), which the table input
   * of the PSD card reads back; null without one. */
  function psdCSV() {
    if (!psd) return null;
    const o = psd.psd && psd.psd.k ? psd.psd : { k: psd.k, P: psd.P, P_err: psd.error && psd.error.P };
    const lines = [`# ljgap ${measured.length ? "psd/combine" : "psd"}: the psd object (SI; k angular, 2 pi int k P dk = h_rms^2)${o.tail ? `; tail exponent ${o.tail.exponent}` : ""}`];
    if (psd.fit) lines.push(`# fit.D = ${psd.fit.D} ± ${psd.error.fit.D}; fit band ${psd.fit.k_min} … ${psd.fit.k_max} [1/m]`);
    if (psd.reliable) lines.push(`# reliable band ${psd.reliable.k_min} … ${psd.reliable.k_max} [1/m] (${psd.reliable.by})`);
    lines.push(`k [1/m],P [m^4]${o.P_err ? ",P_err [m^4]" : ""}`);
    o.k.forEach((k, i) => lines.push([k, o.P[i], ...(o.P_err ? [o.P_err[i]] : [])].join(",")));
    return lines.join("\n") + "\n";
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
    if (measured.length && !psd.psd) {
      $("readout-topo-adhesion").textContent = "The combination has no psd object (see its warnings): no adhesion.";
      return;
    }
    /* several maps: the combined psd object (from the theory's k1 when the combine had the material) */
    const body = { psd: chosen(k1, k2), material: m, units: "SI" };
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
      LJValidity.line(a.model),
      api.metaLine(a),
      ...api.warnings(a)
    );
    api.setIdle(`Adhesion of the measured spectrum: Δγeff/Δγ = ${api.fmt(a.dgamma_eff, 4)}.`);
  }

  function init(helpers) {
    api = helpers;
    $("topo-compute").addEventListener("click", computePsd);
    $("topo-adhesion").addEventListener("click", computeAdhesion);
    $("topo-use").addEventListener("click", useIt);
    $("topo-file").addEventListener("change", () => {
      channels(null); /* a new file: its own channels come with its answer */
      listFiles();
    });
    $("topo-channel").addEventListener("change", computePsd);
    /* a file dropped on the card is the file chosen */
    const card = $("topo-card");
    card.addEventListener("dragover", (e) => {
      e.preventDefault();
      card.classList.add("drop");
    });
    card.addEventListener("dragleave", () => card.classList.remove("drop"));
    card.addEventListener("drop", (e) => {
      e.preventDefault();
      card.classList.remove("drop");
      if (!e.dataTransfer || !e.dataTransfer.files.length) return;
      $("topo-file").files = e.dataTransfer.files;
      $("topo-file").dispatchEvent(new Event("change", { bubbles: true }));
    });
    $("topo-combined-csv").addEventListener("click", () => {
      if (psd && measured.length) api.download("ljgap-topo-combined.csv", new Blob([combinedCSV()], { type: "text/csv" }));
    });
    for (const id of ["topo-k1", "topo-k2"]) $(id).addEventListener("change", () => psd && draw());
    /* any change of the card's inputs (or the material) marks its result */
    for (const ev of ["input", "change"]) document.addEventListener(ev, () => computedFor !== null && markStale());
  }

  return { init, spectrum, cut, query, fileQuery, refused, psdObject, combinedCSV, psdCSV, notText, isInstrument, sourceLine, inputsLine };
})();

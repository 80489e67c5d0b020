/* app.js -- the ljgap page: form -> JSON requests -> plots, readouts and exports.
 *
 * The form is turned into the requests of the API (docs/api.md: traction, pdf, sweep, contact),
 * which run one after another (the server has few compute slots; a 503 is retried after its
 * Retry-After). The server is the only validator of values: text that is not a number is sent as
 * it is, and each problem+json error is shown beside the field whose data-ptr names its JSON
 * pointer (longest prefix wins; a pointer no field claims goes to the panel's readout). Each panel
 * keeps its requests, answers and plotted series, which the export buttons write out as CSV (the
 * server's own CSV of the same requests where it has one: units, summary, SI, errors), JSON
 * (requests, answers, series) and PNG (at 2x, with the parameters), or as curl commands that
 * repeat the exact requests. A run empties the cards it did not ask for and marks the others
 * "computed for" their inputs; a problem moves the view and the focus to the first bad field.
 * Switching "units of the PSD" converts the fields in the PSD's units (k1, k2, the level, a
 * table, the sweep's values) with the material's χ and ε, and back to the same texts.
 */
"use strict";

(() => {
  const $ = (id) => document.getElementById(id);
  const fmt = LJPlots.fmt;
  const errFmt = LJPlots.errFmt;
  const COLORS = ["#1f5fbf", "#d1495b", "#2e933c", "#8e44ad", "#e67e22", "#16a085", "#555"];
  const K0 = Math.cbrt(324 / 3125); /* theory.md §1: the instability (19) below k̃0 */
  const RETRIES = 40; /* 503 answers retried before giving up (Retry-After s apart) */

  /* ---- small helpers ---- */

  /* A number from text; text that is no number goes to the server as it is (it answers 422). */
  function val(text) {
    const t = String(text).trim();
    if (t === "") return undefined;
    if (/^(∞|inf|infinity|null)$/i.test(t)) return null;
    const x = Number(t);
    return Number.isFinite(x) ? x : t;
  }
  const field = (id) => val($(id).value);
  const list = (text) =>
    String(text)
      .split(/[,;\s]+/)
      .filter((t) => t !== "")
      .map(val);
  const el = (tag, attrs = {}, ...kids) => {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs)) {
      if (k === "class") e.className = v;
      else e.setAttribute(k, v);
    }
    for (const k of kids) e.append(k instanceof Node ? k : document.createTextNode(String(k)));
    return e;
  };

  class ClientError extends Error {
    constructor(fieldId, message) {
      super(message);
      this.fieldId = fieldId;
    }
  }

  /* ---- form -> requests ---- */

  /* The table PSD from CSV text: two numbers a line; '#' comments and non-numeric header lines
   * are skipped. */
  function parseTable(text) {
    const k = [];
    const P = [];
    const E = []; /* a third number on every line: P_err (as the topography card exports it) */
    const lines = text.split(/\r?\n/);
    for (let i = 0; i < lines.length; i++) {
      const line = lines[i].replace(/#.*/, "").trim();
      if (line === "") continue;
      const cells = line.split(/[,;\t ]+/).filter((c) => c !== "");
      const nums = cells.map(Number);
      if (cells.length >= 2 && nums.slice(0, 2).every(Number.isFinite)) {
        k.push(nums[0]);
        P.push(nums[1]);
        E.push(cells.length >= 3 && Number.isFinite(nums[2]) ? nums[2] : null);
      } else if (k.length === 0 && cells.some((c) => !Number.isFinite(Number(c)))) {
        continue; /* a header line */
      } else {
        throw new ClientError("table", `line ${i + 1}: expected two numbers "k, P", got "${line}"`);
      }
    }
    if (k.length === 0) throw new ClientError("table", "no (k, P) rows in the table");
    return E.every((e) => e !== null) ? { k, P, P_err: E } : { k, P };
  }

  let loadedTail = null; /* the tail of the spectrum "Use this spectrum" loaded */
  let loadedCorr = null; /* and its knots' correlations {text, P_corr}, while the table is its */
  function psdObject() {
    if (document.querySelector('input[name="kind"]:checked').value === "table") {
      const psd = { kind: "table", ...parseTable($("table").value) };
      const q = field("tail");
      if (q !== undefined) psd.tail = { exponent: q };
      /* a measured spectrum's tail keeps its error while the field holds its exponent */
      if (loadedTail && q === loadedTail.exponent && loadedTail.exponent_err !== undefined) psd.tail.exponent_err = loadedTail.exponent_err;
      /* and its knots' correlations while the table text is the one loaded (issue 29) */
      if (loadedCorr && psd.P_err && $("table").value === loadedCorr.text && loadedCorr.P_corr.length === psd.k.length - 1) psd.P_corr = loadedCorr.P_corr;
      return psd;
    }
    const psd = { kind: "power" };
    psd[$("exp-kind").value] = field("exp");
    psd[$("level-kind").value] = field("level");
    psd.k1 = field("k1");
    if (!$("k2-inf").checked) psd.k2 = field("k2");
    return psd;
  }

  function materialObject() {
    if (!$("use-material").checked) return undefined;
    const m = {};
    if ($("modulus-kind").value === "E_star") m.E_star = field("E_star");
    else for (const id of ["E1", "nu1", "E2", "nu2"]) m[id] = field(id);
    m.dgamma = field("dgamma");
    m.epsilon = field("epsilon");
    return m;
  }

  /* Fields every compute request shares. */
  function common() {
    const c = { psd: psdObject() };
    const method = $("method").value;
    if (method !== "pde") c.method = method;
    const tol = field("tol");
    if (tol !== undefined) c.tol = tol;
    if (method === "paper") {
      const v = list($("vmax").value);
      if (v.length) c.vmax = v[0];
      if ($("fixed-vmax").checked) c.fixed_vmax = true;
    }
    if (method === "montecarlo") {
      const s = field("samples");
      const seed = field("seed");
      if (s !== undefined) c.samples = s;
      if (seed !== undefined) c.seed = seed;
    }
    const m = materialObject();
    if (m) c.material = m;
    if ($("units").value === "SI" && c.psd.kind === "power") c.units = "SI";
    if ($("units").value === "SI" && c.psd.kind === "table") c.units = "SI";
    return c;
  }

  /* Every request the form asks for, by panel, in the order they run. */
  function buildRequests() {
    const base = common();
    const out = [];
    if ($("do-traction").checked) {
      out.push({
        panel: "traction",
        endpoint: "traction",
        body: { ...base, g_ave: { min: field("g-min"), max: field("g-max"), n: field("g-n") } },
      });
    }
    if ($("do-pdf").checked) {
      const body = { ...base, g_ave: field("pdf-g"), k2: list($("pdf-k2").value) };
      const grid = { min: field("grid-min"), max: field("grid-max"), n: field("grid-n") };
      if (Object.values(grid).some((v) => v !== undefined)) body.grid = grid;
      const vmaxes = base.method === "paper" ? list($("vmax").value) : [];
      if (vmaxes.length > 1) {
        for (const v of vmaxes) {
          out.push({ panel: "pdf", endpoint: "pdf", body: { ...body, vmax: v }, label: `Vmax = ${v}` });
        }
      } else {
        out.push({ panel: "pdf", endpoint: "pdf", body });
      }
    }
    if ($("do-sweep").checked) {
      out.push({
        panel: "sweep",
        endpoint: "sweep",
        body: { ...base, vary: $("vary").value, values: list($("values").value) },
      });
    }
    if (base.material && field("R") !== undefined) {
      out.push({ panel: "contact", endpoint: "contact", body: { ...base, R: field("R") } });
    }
    return out;
  }

  /* ---- problems beside their fields ---- */

  const claims = []; /* [pointer prefix, element id, panel or null] */
  function collectClaims(root = document) {
    for (const e of root.querySelectorAll("[data-ptr]")) {
      /* data-panel: the pointer means this field only in that panel's request (/g_ave) */
      for (const p of e.dataset.ptr.split(/\s+/)) claims.push([p, e.id, e.dataset.panel || null]);
    }
  }

  function fieldFor(pointer, panel) {
    let best = null;
    let bestLen = -1;
    for (const [p, id, only] of claims) {
      if (only && only !== panel) continue;
      if (pointer === p || pointer.startsWith(p + "/")) {
        const n = p.length + (only ? 0.5 : 0);
        if (n > bestLen) {
          best = id;
          bestLen = n;
        }
      }
    }
    if (best === null && pointer.startsWith("/psd")) best = "psd-general";
    return best;
  }

  function errorSpan(id) {
    return document.querySelector(`.err[data-for="${id}"]`);
  }

  function showFieldError(id, message) {
    const span = errorSpan(id);
    const input = $(id);
    if (input && input.tagName !== "SPAN") {
      input.classList.add("invalid");
      input.setAttribute("aria-invalid", "true");
    }
    if (!span) return false;
    if (!span.textContent.includes(message)) {
      span.textContent = span.textContent ? `${span.textContent}; ${message}` : message;
    }
    return true;
  }

  function clearErrors() {
    for (const s of document.querySelectorAll(".err")) s.textContent = "";
    for (const i of document.querySelectorAll(".invalid")) {
      i.classList.remove("invalid");
      i.removeAttribute("aria-invalid");
    }
  }

  /* Problems of one answer: beside their fields; the rest as text for the panel. */
  function placeProblem(problem, panel) {
    const loose = [];
    const perField = {};
    for (const e of problem.errors || []) {
      const id = fieldFor(e.pointer || "", panel);
      if (id) perField[id] = (perField[id] || 0) + 1;
      if (id && perField[id] > 3) continue; /* a whole file of bad numbers: the first three */
      if (!id || !showFieldError(id, e.detail)) loose.push(`${e.pointer}: ${e.detail}`);
    }
    for (const [id, n] of Object.entries(perField)) if (n > 3) showFieldError(id, `and ${n - 3} more`);
    if (loose.length > 5) loose.splice(5, loose.length - 5, `and ${loose.length - 5} more problems`);
    return loose;
  }

  /* The first field marked invalid (visible), brought into view and focused: null when none. */
  function focusFirstInvalid() {
    const bad = [...document.querySelectorAll(".invalid")].find((e) => e.offsetParent !== null);
    if (!bad) return null;
    bad.scrollIntoView({ block: "center" });
    bad.focus({ preventScroll: true });
    return bad;
  }

  /* ---- talking to the server ---- */

  let abort = null;
  let tick = null;

  function setBusy(text) {
    const t0 = performance.now();
    $("busy").hidden = false;
    $("cancel").hidden = false;
    $("status").classList.remove("error");
    clearInterval(tick);
    const show = () => {
      $("status-text").textContent = `${text} … ${((performance.now() - t0) / 1000).toFixed(1)} s`;
    };
    show();
    tick = setInterval(show, 100);
  }

  function setIdle(text, isError) {
    clearInterval(tick);
    $("busy").hidden = true;
    $("cancel").hidden = true;
    $("status-text").textContent = text;
    $("status").classList.toggle("error", !!isError);
  }

  const sleep = (ms, signal) =>
    new Promise((resolve, reject) => {
      const t = setTimeout(resolve, ms);
      signal.addEventListener("abort", () => {
        clearTimeout(t);
        reject(new DOMException("cancelled", "AbortError"));
      });
    });

  /* POST the exact text to /v1/endpoint (JSON, or opts.contentType with opts.query); retries 503
   * after Retry-After. -> {status, json} */
  async function post(endpoint, text, signal = new AbortController().signal, opts = {}) {
    const url = `/v1/${endpoint}${opts.query ? `?${opts.query}` : ""}`;
    for (let attempt = 0; ; attempt++) {
      const r = await fetch(url, {
        method: "POST",
        headers: { "Content-Type": opts.contentType || "application/json" },
        body: text,
        signal,
      });
      if (r.status === 503 && attempt < RETRIES) {
        const s = Number(r.headers.get("Retry-After")) || 1;
        await r.text();
        await sleep(1000 * Math.min(s, 10), signal);
        continue;
      }
      let json = null;
      try {
        json = await r.json();
      } catch (e) {
        json = { title: `HTTP ${r.status}`, detail: "the answer was not JSON" };
      }
      return { status: r.status, json };
    }
  }

  /* ---- panels ---- */

  const panels = {}; /* name -> {title, requests:[{endpoint,text,label}], answers:[], series:[], xName} */
  const panelNames = ["traction", "pdf", "sweep", "psd", "contact", "jobs", "topo"];
  const plotTitles = {
    traction: "Mean traction against mean gap",
    pdf: "Gap probability density",
    sweep: "Sweep",
    psd: "Power spectral density",
    contact: "Sphere contact",
    jobs: "Numerical model against the statistical theory",
    topo: "Measured topography: isotropic PSD and its power-law fit",
  };

  function resetPanel(name) {
    panels[name] = { title: plotTitles[name], requests: [], answers: [], series: [], xName: "x" };
    return panels[name];
  }

  function metaLine(ans) {
    const m = ans.meta || {};
    const parts = [`${m.method || "?"}`, `${fmt(m.elapsed_ms, 3)} ms`];
    if (m.cached) parts.push("cached");
    return el("div", { class: "meta" }, `method ${parts.join(" · ")} (version ${m.version || "?"})`);
  }

  function warnings(ans) {
    const w = (ans.meta && ans.meta.warnings) || [];
    return w.map((t) => el("div", { class: "warn" }, `⚠ ${t}`));
  }

  function row(name, value, err, si) {
    const tr = el("tr", {}, el("th", {}, name), el("td", {}, fmt(value)));
    tr.append(el("td", {}, err === undefined ? "" : `± ${errFmt(err)}`));
    if (si !== undefined) tr.append(el("td", {}, si));
    return tr;
  }

  /* "Δγeff/Δγ = x ± y (measurement) ± z (solver)": the measurement's uncertainty ie (1 σ, the
   * answer's input_error) beside the solver's error e; nothing without ie. */
  function uncertLine(s, e, ie) {
    if (!ie || typeof ie.dgamma_eff !== "number") return [];
    return [el("div", { class: "uncert" }, `Δγeff/Δγ = ${fmt(s.dgamma_eff, 3)} ± ${fmt(ie.dgamma_eff, 2)} (measurement) ± ${errFmt(e.dgamma_eff)} (solver)`)];
  }

  /* The adhesion fields s with their errors e; with a material, in SI too (si, its errors sie);
   * ie: the measurement's uncertainty (an adhesion answer's own input_error when not given). */
  function summaryTable(s, e, si, sie, ie) {
    ie = ie || s.input_error;
    e = e || {};
    si = si || {};
    sie = sie || {};
    const pm = (k) => (typeof sie[k] === "number" ? ` ± ${errFmt(sie[k])}` : "");
    const siv = (k, unit) => (si[k] !== undefined ? `${fmt(si[k], 4)}${pm(k)} ${unit}` : undefined);
    const hasSI = Object.keys(si).length > 0;
    return el(
      "table",
      {},
      ...uncertLine(s, e, ie).map((d) => el("caption", {}, d)),
      el("tr", {}, ...["quantity", "value (ε, σ0, Δγ)", "± err", ...(hasSI ? ["SI"] : [])].map((h) => el("th", {}, h))),
      row("g̃eq", s.g_eq, e.g_eq, siv("g_eq_m", "m")),
      row("σ̄max/σ0", s.sigma_max, e.sigma_max, siv("sigma_max_Pa", "Pa")),
      row("at g̃ave", s.g_at_max, e.g_at_max, siv("g_at_max_m", "m")),
      row("Δγeff/Δγ", s.dgamma_eff, e.dgamma_eff, siv("dgamma_eff_J_m2", "J/m²")),
      row("m̃0", s.m0, undefined, siv("m0_m2", "m²"))
    );
  }

  const flatLJ = (g) => (3 * Math.sqrt(3) / 2) * (Math.pow(g, -3) - Math.pow(g, -9));
  const maxAbs = (a) => a.reduce((m, v) => Math.max(m, Math.abs(v)), 0);

  /* Plots in SI: with a material (its answers have si) unless the switch says dimensionless. */
  const siPlots = (ans) => !!(ans && ans.si && $("si-plots").checked);

  function showTraction(p, ans) {
    const s = ans.summary;
    const si = siPlots(ans);
    /* in SI: gaps in m (ε g̃), tractions in Pa (σ0 σ̄/σ0) */
    const gx = si ? ans.si.g_ave_m[0] / ans.g_ave[0] : 1; /* ε */
    const sy = si ? ans.si.sigma0_Pa : 1;
    const g = ans.g_ave.map((x) => x * gx);
    const sig = ans.sigma.map((v) => v * sy);
    const area = ans.g_ave.map((x, i) => (s.g_eq !== null && x >= s.g_eq ? sig[i] : null));
    /* the measurement's uncertainty, ±1 σ about the curve (input_error.sigma), as a band */
    const ie = ans.input_error && (si ? ans.si.input_error.sigma_Pa : ans.input_error.sigma);
    const side = (f) => sig.map((v, i) => (ie && typeof ie[i] === "number" ? v + f * ie[i] : null));
    const flat = ans.g_ave.map((x) => flatLJ(x) * sy);
    p.xName = si ? "g_ave [m]" : "g_ave";
    p.series = [
      { name: si ? "σ̄ (rough, Pa)" : "σ̄/σ0 (rough)", x: g, y: sig, err: si ? ans.si.error.sigma_Pa : ans.error.sigma, color: COLORS[0] },
      { name: si ? "σ flat LJ (8), Pa" : "σ/σ0 flat LJ (8)", x: g, y: flat, color: "#777", dash: [6, 4], width: 1.5 },
      {
        name: "Δγeff area",
        x: g,
        y: area,
        color: "rgba(31,95,191,0.0)",
        fill: "rgba(31,95,191,0.18)",
        width: 0,
      },
    ];
    const bands = [];
    if (ie) {
      const n = p.series.length;
      p.series.push(
        { name: "σ̄ + input_error (1σ)", x: g, y: side(1), color: "rgba(214,120,20,0.7)", width: 1 },
        { name: "σ̄ − input_error (1σ)", x: g, y: side(-1), color: "rgba(214,120,20,0.7)", width: 1 }
      );
      bands.push({ hi: n, lo: n + 1, fill: "rgba(214,120,20,0.16)" });
    }
    const pos = Math.max(...sig.filter(Number.isFinite), ...flat);
    const marks = [];
    if (s.g_eq !== null) {
      marks.push({ type: "vline", x: s.g_eq * gx, label: si ? `geq = ${fmt(s.g_eq * gx, 4)} m` : `g̃eq = ${fmt(s.g_eq, 4)}`, color: "#2e933c" });
    }
    if (s.sigma_max !== null) {
      marks.push({
        type: "point",
        x: s.g_at_max * gx,
        y: s.sigma_max * sy,
        label: si ? `σ̄max = ${fmt(s.sigma_max * sy, 4)} Pa` : `σ̄max/σ0 = ${fmt(s.sigma_max, 4)}`,
        color: "#d1495b",
      });
    }
    LJPlots.draw($("plot-traction"), {
      title: plotTitles.traction,
      xLabel: si ? "gave (m)" : "g̃ave",
      xName: si ? "gave (m)" : "g̃ave",
      yLabel: si ? "σ̄ (Pa)" : "σ̄/σ0",
      series: p.series,
      bands,
      marks,
      params: p.params,
      yClamp: [-1.5 * pos, 1.05 * sy],
    });
    const ro = $("readout-traction");
    ro.replaceChildren(
      summaryTable(s, ans.error.summary, ans.si && ans.si.summary, ans.si && ans.si.error.summary, ans.input_error && ans.input_error.summary),
      el(
        "div",
        { class: "meta" },
        `curve: ${g.length} points, largest error ${errFmt(maxAbs(ans.error.sigma))}; shaded: the area beyond g̃eq (Δγeff)${ie ? "; orange band: ± the measurement's uncertainty (input_error, 1 σ)" : ""}`
      ),
      forLine(p),
      LJValidity.line(ans.model),
      metaLine(ans),
      ...warnings(ans)
    );
  }

  const forLine = (p) => el("div", { class: "meta computed-for" }, `computed for: ${p.params || "—"}`);

  function k2Label(k) {
    return k === null ? "∞" : String(k);
  }

  function showPdf(p, results) {
    p.xName = "g";
    p.series = [];
    const ro = $("readout-pdf");
    const t = el("table", {}, el("tr", {}, ...["curve", "mass", "mean g̃ (ε)", "σ̄/σ0", "± err", "‖ΔΦ‖₁ err"].map((h) => el("th", {}, h))));
    const metas = [];
    let c = 0;
    for (const { ans, label } of results) {
      ans.pdfs.forEach((pdf, i) => {
        const name = label ? `${label}, k̃2 = ${k2Label(pdf.k2)}` : `k̃2 = ${k2Label(pdf.k2)}`;
        const e = (ans.error.pdfs || [])[i] || {};
        const sp = siPlots(ans) ? ans.si.pdfs[i] : null; /* in SI: g in m, Φ in 1/m */
        p.series.push({ name, x: sp ? sp.g_m : pdf.g, y: sp ? sp.phi_per_m : pdf.phi, color: COLORS[c++ % COLORS.length], errL1: e.phi_l1 });
        t.append(
          el(
            "tr",
            {},
            el("td", {}, name),
            el("td", {}, fmt(pdf.mass)),
            el("td", {}, fmt(pdf.mean)),
            el("td", {}, fmt(pdf.sigma)),
            el("td", {}, errFmt(e.sigma)),
            el("td", {}, errFmt(e.phi_l1))
          )
        );
      });
      metas.push(LJValidity.line(ans.model), metaLine(ans), ...warnings(ans));
    }
    /* the x axis over where the densities live (Φ above 1e-4 of its peak), not the whole grid */
    let lo = Infinity;
    let hi = -Infinity;
    for (const s of p.series) {
      const top = Math.max(...s.y.filter(Number.isFinite));
      s.x.forEach((x, i) => {
        if (s.y[i] > 1e-4 * top) (lo = Math.min(lo, x)), (hi = Math.max(hi, x));
      });
    }
    const pdfSI = siPlots(results[0].ans);
    LJPlots.draw($("plot-pdf"), {
      title: `${plotTitles.pdf} at g̃ave = ${fmt(results[0].body.g_ave)}`,
      xLabel: pdfSI ? "g (m)" : "g̃",
      xName: pdfSI ? "g (m)" : "g̃",
      yLabel: pdfSI ? "Φ (1/m)" : "Φ(g̃)",
      series: p.series,
      yZero: true,
      params: p.params,
      xRange: hi > lo ? [lo - 0.03 * (hi - lo), hi + 0.03 * (hi - lo)] : undefined,
    });
    ro.replaceChildren(t, forLine(p), ...metas);
  }

  /* A sweep's variable in SI and dimensionless: its label with the unit, and the factor
   * SI value = dimensionless value × factor (api.md "Physical units"; D has none). */
  function sweepScale(vary, body, ans) {
    const chi = ans.si && ans.si.chi_m;
    const eps = body.material && body.material.epsilon;
    const D = body.psd.D !== undefined ? body.psd.D : 3 - body.psd.H;
    const f = { m0: eps * eps, k1: 1 / chi, C: eps * eps * Math.pow(chi, 2 * D - 6), D: 1 }[vary];
    return Number.isFinite(f) && f > 0 ? f : null;
  }
  const sweepNames = { m0: "m̃0 (ε²)", C: "C̃", D: "D", k1: "k̃1 (1/χ)" };
  const sweepNamesSI = { m0: "m0 (m²)", C: "C (m^(2D−4))", D: "D", k1: "k1 (1/m)" };

  function showSweep(p, ans, body) {
    const r = ans.results;
    const siReq = body.units === "SI"; /* the values went in SI */
    const f = ans.si ? sweepScale(ans.vary, body, ans) : null;
    /* the x axis in SI when the plots are (a material and the switch), else dimensionless */
    const inSI = f !== null && siPlots(ans);
    let x = ans.values.map((v) => (inSI === siReq ? v : inSI ? v * f : v / f));
    let xName = (inSI || (siReq && f === null) ? sweepNamesSI : sweepNames)[ans.vary] || ans.vary;
    /* uPlot draws nothing on a log axis below about 1e-17: m0 in nm², anything else that small
     * in units of a power of ten that the label names */
    const lo = Math.min(...x.filter((v) => v > 0));
    if (xName === sweepNamesSI.m0) {
      x = x.map((v) => v * 1e18);
      xName = "m0 (nm²)";
    } else if (lo < 1e-12) {
      const e = Math.floor(Math.log10(lo));
      x = x.map((v) => v / Math.pow(10, e));
      xName = `${xName} / 1e${e}`;
    }
    const get = (k) => r.map((o) => (o ? o[k] : null));
    const errs = (k) => r.map((o) => (o && o.error ? o.error[k] : null));
    p.xName = xName;
    p.series = [
      { name: "Δγeff/Δγ", x, y: get("dgamma_eff"), err: errs("dgamma_eff"), color: COLORS[0], points: true },
      { name: "σ̄max/σ0", x, y: get("sigma_max"), err: errs("sigma_max"), color: COLORS[1], points: true },
    ];
    const logX = ans.vary !== "D" && x.every((v) => v > 0);
    LJPlots.draw($("plot-sweep"), {
      title: `${plotTitles.sweep} over ${xName}`,
      xLabel: xName,
      xName,
      yLabel: "Δγeff/Δγ, σ̄max/σ0 (ratios)",
      xLog: logX,
      /* an explicit range: uPlot's own log range fails on values as small as 1e-20 (m0 in m²) */
      xRange: logX ? [Math.min(...x) / 1.3, Math.max(...x) * 1.3] : undefined,
      series: p.series,
      params: p.params,
      yZero: true,
    });
    const sir = (ans.si && ans.si.results) || [];
    const heads = [xName, "g̃eq (ε)", "σ̄max/σ0", "Δγeff/Δγ", "largest ± err (of the three)"];
    if (sir.length) heads.push("geq (m)", "σ̄max (Pa)", "Δγeff (J/m²)");
    const t = el("table", {}, el("tr", {}, ...heads.map((h) => el("th", {}, h))));
    r.forEach((o, i) => {
      const e = (o && o.error) || {};
      const worst = Math.max(...["g_eq", "sigma_max", "dgamma_eff"].map((k) => Math.abs(e[k] || 0)));
      const tr = el("tr", {}, el("td", {}, fmt(x[i])), el("td", {}, fmt(o && o.g_eq)), el("td", {}, fmt(o && o.sigma_max)), el("td", {}, fmt(o && o.dgamma_eff)), el("td", {}, errFmt(worst)));
      if (sir.length) {
        const q = sir[i];
        tr.append(el("td", {}, fmt(q && q.g_eq_m, 4)), el("td", {}, fmt(q && q.sigma_max_Pa, 4)), el("td", {}, fmt(q && q.dgamma_eff_J_m2, 4)));
      }
      t.append(tr);
    });
    const worstAll = Math.max(...r.map((o) => Math.max(...Object.values((o && o.error) || {}).map(Math.abs))));
    const details = el("details", {}, el("summary", {}, `${x.length} points, largest error ${errFmt(worstAll)}: table`), t);
    $("readout-sweep").replaceChildren(details, forLine(p), LJValidity.sweepLine(r), metaLine(ans), ...warnings(ans));
  }

  /* The PSD as the form gives it (client side: a picture of the input, with its cut-offs). */
  function showPsd(req, traction) {
    const p = panels.psd;
    const psd = req.psd;
    const si = req.units === "SI";
    const marks = [];
    let k0 = si ? null : K0;
    if (si && traction && traction.si && traction.si.chi_m) k0 = K0 / traction.si.chi_m;
    p.xName = "k";
    const logspace = (a, b, n) => Array.from({ length: n }, (_, i) => a * Math.pow(b / a, i / (n - 1)));
    const notes = [];
    if (psd.kind === "table") {
      p.series = [{ name: "P̃S table", x: psd.k, y: psd.P, color: COLORS[0], points: true }];
      const q = psd.tail && psd.tail.exponent;
      const n = psd.k.length;
      if (typeof q === "number" && n) {
        const kk = logspace(psd.k[n - 1], psd.k[n - 1] * 100, 40);
        p.series.push({ name: `tail ∝ k^${q}`, x: kk, y: kk.map((k) => psd.P[n - 1] * Math.pow(k / psd.k[n - 1], q)), color: COLORS[1], dash: [6, 4] });
      }
      marks.push({ type: "vline", x: psd.k[0], label: "first k", color: "#2e933c" });
    } else {
      const D = psd.D !== undefined ? psd.D : 3 - psd.H;
      const k1 = psd.k1;
      const k2 = psd.k2 === undefined ? null : psd.k2;
      if (![D, k1].every((v) => typeof v === "number") || (k2 !== null && typeof k2 !== "number")) {
        LJPlots.clear($("plot-psd"));
        $("readout-psd").textContent = "Give D (or H) and the cut-offs as numbers to see the spectrum.";
        return;
      }
      const a = 2 * D - 6; /* m0 = 2πC ∫ k^(2D−7) dk = 2πC (k2^a − k1^a)/a */
      const band = (k2 === null ? 0 - Math.pow(k1, a) : Math.pow(k2, a) - Math.pow(k1, a)) / a;
      let C = psd.C;
      if (C === undefined && typeof psd.m0 === "number") C = psd.m0 / (2 * Math.PI * band);
      if (C === undefined && typeof psd.h_rms === "number") C = (psd.h_rms * psd.h_rms) / (2 * Math.PI * band);
      if (typeof C !== "number" || !(C > 0) || !(band > 0)) {
        LJPlots.clear($("plot-psd"));
        $("readout-psd").textContent = "The level or the exponent is not usable for a picture (k̃2 = ∞ needs D < 3).";
        return;
      }
      const top = k2 === null ? k1 * 1000 : k2;
      const kk = logspace(k1, top, 80);
      p.series = [{ name: `C k^(2D−8), D = ${fmt(D)}`, x: kk, y: kk.map((k) => C * Math.pow(k, 2 * D - 8)), color: COLORS[0] }];
      marks.push({ type: "vline", x: k1, label: si ? "k1" : "k̃1", color: "#2e933c" });
      if (k2 !== null) marks.push({ type: "vline", x: k2, label: si ? "k2" : "k̃2", color: "#2e933c" });
      else notes.push(si ? "k2 = ∞: drawn to 1000 k1" : "k̃2 = ∞: drawn to 1000 k̃1");
      notes.push(`C = ${fmt(C)}${si ? ` m^${fmt(2 * D - 4, 3)}` : ""}${psd.C === undefined ? " (from the level given)" : ""}`);
    }
    if (k0 !== null) marks.push({ type: "vline", x: k0, label: si ? "k0 = 0.46978/χ" : "k̃0 (instability)", color: "#d1495b", dash: [2, 3], row: 1 });
    if (traction) notes.push(`m̃0 = ${fmt(traction.summary.m0)} (server)`);
    /* the x range takes in k̃0 so that the distance of k̃1 from the instability shows */
    const xs = p.series.flatMap((s) => s.x).concat(k0 !== null ? [k0] : []);
    const xRange = [Math.min(...xs) / 1.5, Math.max(...xs) * 1.5];
    LJPlots.draw($("plot-psd"), {
      title: plotTitles.psd,
      xLabel: si ? "k (1/m)" : "k̃",
      xName: si ? "k" : "k̃",
      yLabel: si ? "PS (m⁴)" : "P̃S",
      xLog: true,
      yLog: true,
      xRange,
      series: p.series,
      marks,
    });
    $("readout-psd").replaceChildren(el("div", { class: "meta" }, notes.join(" · ") || "table as given"));
    LJValidity.draw($("validity-map"), traction && traction.model); /* where the request sits on the map */
  }

  function showContact(p, ans) {
    const e = ans.error || {};
    const pe = e.pull_off_N || {};
    const po = ans.pull_off_N || {};
    const t = el("table", {}, el("tr", {}, ...["quantity", "value", "unit", "± err"].map((h) => el("th", {}, h))));
    const names = { jkr_smooth: "pull-off, JKR, flat Δγ", jkr: "pull-off, JKR with Δγeff", dmt: "pull-off, DMT with Δγeff", maugis_dugdale: "pull-off, Maugis–Dugdale" };
    for (const k of Object.keys(po)) t.append(el("tr", {}, el("td", {}, names[k] || k), el("td", {}, fmt(po[k], 4)), el("td", {}, "N"), el("td", {}, errFmt(pe[k]))));
    const tb = ans.tabor || {};
    t.append(el("tr", {}, el("td", {}, "Tabor μ (flat / effective)"), el("td", {}, `${fmt(tb.smooth, 4)} / ${fmt(tb.effective, 4)}`), el("td", {}, "1"), el("td", {}, errFmt(e.tabor && e.tabor.effective))));
    t.append(el("tr", {}, el("td", {}, "Maugis λ"), el("td", {}, fmt(ans.maugis_lambda, 4)), el("td", {}, "1"), el("td", {}, errFmt(e.maugis_lambda))));
    t.append(el("tr", {}, el("td", {}, "regime"), el("td", {}, ans.regime || "—"), el("td", {}, ""), el("td", {}, "")));
    p.series = [{ name: "pull_off_N", x: Object.keys(po), y: Object.values(po), err: Object.keys(po).map((k) => pe[k]) }];
    p.xName = "model";
    $("card-contact").hidden = false;
    $("readout-contact").replaceChildren(t, forLine(p), LJValidity.line(ans.model), metaLine(ans), ...warnings(ans));
  }

  /* A problem answer of panel's request: beside the fields its pointers name, the rest in the
   * panel's readout. */
  function showProblem(panel, status, json) {
    json = json || {};
    const loose = placeProblem(json, panel);
    const ro = $(`readout-${panel}`);
    ro.replaceChildren(
      el("div", { class: "problem" }, `${status} ${json.title || ""}: ${json.detail || ""}`),
      ...loose.map((t) => el("div", { class: "problem" }, t))
    );
    panels[panel].failed = true;
    if (panel === "contact") $("card-contact").hidden = false;
    else if ($(`plot-${panel}`)) LJPlots.clear($(`plot-${panel}`));
  }

  /* ---- running ---- */

  let running = false;

  /* The inputs a result was computed for, in one line (the "computed for" of each card). */
  function describe(base) {
    const q = base.psd;
    const si = base.units === "SI";
    const parts = [];
    if (q.kind === "table") {
      parts.push(`table PSD of ${q.k.length} points, k ${fmt(q.k[0], 4)} … ${fmt(q.k[q.k.length - 1], 4)}${si ? " 1/m" : ""}${q.tail ? `, tail k^${fmt(q.tail.exponent, 4)}` : ""}`);
    } else {
      for (const key of ["D", "H", "C", "m0", "h_rms", "k1"]) if (q[key] !== undefined) parts.push(`${key} = ${q[key]}`);
      parts.push(`k2 = ${q.k2 === undefined || q.k2 === null ? "∞" : q.k2}`);
    }
    parts.push(si ? "SI" : "dimensionless");
    if (base.method) parts.push(`method ${base.method}`);
    const m = base.material;
    if (m) parts.push(`material ${Object.entries(m).map(([k, v]) => `${k} = ${v}`).join(", ")}`);
    return parts.join("; ");
  }

  /* A card with no result (a run that did not ask for it): empty, so nothing stale stays. */
  function emptyPanel(name) {
    resetPanel(name);
    if ($(`plot-${name}`)) LJPlots.clear($(`plot-${name}`));
    if ($(`readout-${name}`)) $(`readout-${name}`).textContent = "No result yet.";
  }

  /* Export buttons live only on a card with something to export. */
  function updateExports() {
    for (const box of document.querySelectorAll(".exports")) {
      const p = panels[box.dataset.panel];
      /* CSV and PNG need a result; JSON and curl also carry a refused request and its problem */
      const drawn = !!p && p.series.length > 0;
      const asked = !!p && (drawn || p.answers.length > 0);
      for (const b of box.querySelectorAll("button")) b.disabled = /^(csv|png)$/.test(b.dataset.export) ? !drawn : !asked;
    }
  }

  async function run(opts = {}) {
    if (running) return;
    clearErrors();
    let reqs;
    try {
      reqs = buildRequests();
    } catch (e) {
      if (e instanceof ClientError) {
        showFieldError(e.fieldId, e.message);
        focusFirstInvalid();
        setIdle("Fix the highlighted field.", true);
        return;
      }
      throw e;
    }
    const base = common();
    running = true;
    $("compute").disabled = true;
    $("compute-top").disabled = true;
    abort = new AbortController();
    /* every calculation card starts afresh: those not asked for this time are emptied (a result
     * of other inputs must not stay beside this one's) */
    for (const n of ["traction", "pdf", "sweep", "contact"]) {
      if (reqs.some((r) => r.panel === n)) resetPanel(n).params = describe(base);
      else emptyPanel(n);
    }
    resetPanel("psd").params = describe(base);
    if (!reqs.some((r) => r.panel === "contact")) $("card-contact").hidden = true;
    showPsd(base, null);
    const byPanel = {};
    let failed = 0;
    let done = 0;
    try {
      for (const r of reqs) {
        const text = JSON.stringify(r.body);
        const p = panels[r.panel];
        p.requests.push({ endpoint: r.endpoint, text, label: r.label });
        const card = $(`card-${r.panel}`);
        card.classList.add("busy");
        setBusy(`${r.endpoint}${r.label ? ` (${r.label})` : ""}: request ${done + 1} of ${reqs.length}`);
        let res;
        try {
          res = await post(r.endpoint, text, abort.signal);
        } finally {
          card.classList.remove("busy");
        }
        done++;
        p.answers.push(res.json);
        if (res.status >= 200 && res.status < 300) {
          (byPanel[r.panel] = byPanel[r.panel] || []).push({ ans: res.json, label: r.label, body: r.body });
        } else {
          failed++;
          showProblem(r.panel, res.status, res.json);
        }
        const got = byPanel[r.panel];
        if (got && got.length === reqs.filter((q) => q.panel === r.panel).length) {
          const p0 = panels[r.panel];
          if (r.panel === "traction") {
            showTraction(p0, got[0].ans);
            showPsd(base, got[0].ans);
          } else if (r.panel === "pdf") showPdf(p0, got);
          else if (r.panel === "sweep") showSweep(p0, got[0].ans, got[0].body);
          else if (r.panel === "contact") showContact(p0, got[0].ans);
        }
      }
      if (failed) {
        const bad = focusFirstInvalid();
        const cards = [...new Set(reqs.filter((r) => panels[r.panel].failed).map((r) => r.panel))];
        if (!bad) $(`card-${cards[0]}`).scrollIntoView({ block: "start" });
        setIdle(`${failed} of ${reqs.length} requests answered with a problem: ${bad ? `see the highlighted field${document.querySelectorAll(".invalid").length > 1 ? "s" : ""}` : `see the ${cards.length > 1 ? `${cards.slice(0, -1).join(", ")} and ${cards[cards.length - 1]}` : cards[0]} card${cards.length > 1 ? "s" : ""}`}.`, true);
      } else {
        setIdle(`Done: ${reqs.length} request${reqs.length === 1 ? "" : "s"}.`);
        const first = reqs.length ? $(`card-${reqs[0].panel}`) : null;
        if (first && !opts.stay) {
          const r = first.getBoundingClientRect();
          if (r.top < 0 || r.top > innerHeight * 0.6) first.scrollIntoView({ block: "start" });
        }
      }
    } catch (e) {
      if (e.name === "AbortError") setIdle("Cancelled.", true);
      else setIdle(`Request failed: ${e.message}`, true);
    } finally {
      running = false;
      $("compute").disabled = false;
      $("compute-top").disabled = false;
      abort = null;
      updateExports();
    }
  }

  /* A measured spectrum (the SI psd object of /v1/psd or /v1/psd/combine) as the calculation's
   * PSD with the form's material: the form switches to that table in SI, the gaps are placed
   * about its g̃eq (asked of /v1/adhesion), and the traction, the PDF at g̃eq and, with a sphere
   * radius, the pull-off run and are drawn. */
  async function useSpectrum(q, label) {
    if (running) return;
    document.querySelector('input[name="kind"][value="table"]').checked = true;
    const head = `k [1/m], P [m^4]${q.P_err ? ", P_err [m^4]" : ""}`;
    const rows = q.k.map((k, i) => [k, q.P[i], ...(q.P_err ? [q.P_err[i]] : [])].join(", "));
    $("table").value = [`# ${label}`, head, ...rows].join("\n");
    $("tail").value = q.tail ? String(q.tail.exponent) : "";
    loadedTail = q.tail || null;
    loadedCorr = q.P_corr && q.P_err ? { text: $("table").value, P_corr: q.P_corr } : null;
    if (unitsNow !== "SI") convertFields(true, { table: false }); /* the power law's fields and the sweep follow */
    $("units").value = "SI";
    unitsNow = "SI";
    $("do-traction").checked = true;
    $("do-pdf").checked = true;
    $("do-sweep").checked = false;
    /* the PDF's k̃2 (dimensionless, as the server reads it): ∞ needs a tail, else the table's end */
    const chiNow = chiOf(materialObject());
    $("pdf-k2").value = q.tail || !chiNow ? "∞" : numText(q.k[q.k.length - 1] * chiNow);
    for (const id of ["grid-min", "grid-max", "grid-n"]) $(id).value = "";
    $("method").value = "pde";
    $("preset-note").textContent = `The measured spectrum (${label}) in SI with the material above.`;
    syncVisibility();
    const base = common();
    setBusy("adhesion of the measured spectrum (for the range of gaps)");
    const res = await post("adhesion", JSON.stringify({ psd: base.psd, material: base.material, units: "SI" }));
    if (res.status === 200 && Number.isFinite(res.json.g_eq)) {
      const g = res.json.g_eq;
      $("g-min").value = fmt(Math.max(0.5, 0.85 * g), 4);
      $("g-max").value = fmt(Math.max(2 * g, g + 2), 4);
      $("pdf-g").value = fmt(g, 5);
    }
    setIdle("");
    await run({ stay: true });
    $("card-traction").scrollIntoView({ block: "start" });
  }

  /* ---- exports ---- */

  function download(name, blob) {
    const a = el("a", { href: URL.createObjectURL(blob), download: name });
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  }

  const csvCell = (v) => {
    if (v === null || v === undefined) return "";
    const s = String(v);
    return /[",\n]/.test(s) ? `"${s.replace(/"/g, '""')}"` : s;
  };

  /* The server's own CSV (docs/api.md "CSV": units, the summary, SI and the errors) of each
   * request of the panel it answered, one after another with the request as a # line; the
   * panels whose answers have no CSV form write their series with units (pageCSV). */
  const SERVER_CSV = ["traction", "pdf", "sweep"];
  async function panelCSV(name) {
    const p = panels[name];
    if (name === "contact") return contactCSV(p);
    if (name === "topo") return (typeof LJTopo !== "undefined" && LJTopo.psdCSV()) || pageCSV(name);
    if (!SERVER_CSV.includes(name)) return pageCSV(name);
    const parts = [];
    for (const [i, r] of p.requests.entries()) {
      const a = p.answers[i];
      if (!a || (a.type && a.status >= 400)) continue; /* a refused request has no CSV */
      const res = await fetch(`/v1/${r.endpoint}`, { method: "POST", headers: { "Content-Type": "application/json", Accept: "text/csv" }, body: r.text });
      const text = await res.text();
      if (!res.ok) throw new Error(`the server's CSV of ${r.endpoint}: ${res.status}`);
      parts.push(`# request: POST /v1/${r.endpoint}${r.label ? ` (${r.label})` : ""} ${r.text}\n${text}`);
    }
    return parts.join("\n");
  }

  /* The pull-off card as CSV: one row a quantity, with its unit and error. */
  function contactCSV(p) {
    const a = p.answers.find((x) => x && x.pull_off_N) || {};
    const e = a.error || {};
    const lines = [`# ljgap contact: ${p.params || ""}`, "quantity,value,unit,error"];
    for (const [k, v] of Object.entries(a.pull_off_N || {})) lines.push([`pull_off_N.${k}`, v, "N", (e.pull_off_N || {})[k]].map(csvCell).join(","));
    const tb = a.tabor || {};
    for (const k of Object.keys(tb)) lines.push([`tabor.${k}`, tb[k], "1", (e.tabor || {})[k]].map(csvCell).join(","));
    lines.push(["maugis_lambda", a.maugis_lambda, "1", e.maugis_lambda].map(csvCell).join(","));
    lines.push(["regime", a.regime, "", ""].map(csvCell).join(","));
    return lines.join("\n") + "\n";
  }

  /* Every plotted series of a panel, long form: series, x, y, error, with the axes' units. */
  function pageCSV(name) {
    const p = panels[name];
    const fig = $(`plot-${name}`) ? LJPlots.figure($(`plot-${name}`)) : null;
    const lines = [`# ljgap ${name}: ${p.params || p.title}`];
    lines.push(["series", fig ? fig.xLabel : p.xName, fig ? `value: ${fig.yLabel}` : "value", "error"].map(csvCell).join(","));
    for (const s of p.series) {
      s.x.forEach((x, i) => {
        if (s.y[i] === null || s.y[i] === undefined) return;
        lines.push([s.name, x, s.y[i], s.err ? s.err[i] : ""].map(csvCell).join(","));
      });
    }
    return lines.join("\n") + "\n";
  }

  function panelJSON(name) {
    const p = panels[name];
    return JSON.stringify(
      {
        panel: name,
        requests: p.requests.map((r) => ({ url: `${location.origin}/v1/${r.endpoint}`, label: r.label, body: JSON.parse(r.text) })),
        answers: p.answers,
        series: p.series.map((s) => ({ name: s.name, x: s.x, y: s.y, error: s.err, error_l1: s.errL1 })),
      },
      null,
      1
    );
  }

  const shellQuote = (s) => `'${s.replace(/'/g, `'\\''`)}'`;

  function panelCurl(name) {
    return panels[name].requests
      .map((r) => `curl -s ${location.origin}/v1/${r.endpoint} -H 'Content-Type: application/json' -d ${shellQuote(r.text)}`)
      .join("\n");
  }

  async function copyCurl(name) {
    const text = panelCurl(name);
    $("curl-text").value = text;
    if (!$("curl-dialog").open) $("curl-dialog").showModal();
    $("curl-text").select();
    try {
      await navigator.clipboard.writeText(text);
      setIdle("curl command copied to the clipboard.");
    } catch (e) {
      setIdle("Select the text in the box and copy it (the browser refused clipboard access).");
    }
  }

  const cardNames = { traction: "Traction", pdf: "PDF", sweep: "Sweep", psd: "PSD", contact: "Pull-off", jobs: "Simulation", topo: "Topography" };

  function addExports() {
    for (const box of document.querySelectorAll(".exports")) {
      const name = box.dataset.panel;
      const b = (label, fn) => {
        /* named by its card ("Traction CSV"), for the eye and for a screen reader */
        const btn = el("button", { type: "button", "data-export": label.toLowerCase().replace(/ /g, "-"), disabled: "" }, `${cardNames[name]} ${label}`);
        btn.addEventListener("click", async () => {
          if (!panels[name] || (!panels[name].series.length && !panels[name].requests.length)) {
            setIdle("Nothing to export yet: compute first.", true);
            return;
          }
          try {
            await fn();
          } catch (e) {
            setIdle(`Export failed: ${e.message}`, true);
          }
        });
        box.append(btn);
      };
      b("CSV", async () => download(`ljgap-${name}.csv`, new Blob([await panelCSV(name)], { type: "text/csv" })));
      b("JSON", () => download(`ljgap-${name}.json`, new Blob([panelJSON(name)], { type: "application/json" })));
      if (name !== "contact") {
        b("PNG", async () => {
          const blob = await LJPlots.toPNG($(`plot-${name}`), panels[name].params);
          if (blob) download(`ljgap-${name}.png`, blob);
        });
      }
      if (name !== "psd" && name !== "topo") b("Copy as curl", () => copyCurl(name));
    }
  }

  /* ---- presets (README "Reproducing the paper's figures") ---- */

  const C4 = "0.0795775"; /* 1/(4π): the paper's figures, theory.md §4 */
  const defaults = {
    kind: "power", "exp-kind": "D", exp: "2.5", "level-kind": "C", level: C4, k1: "1", k2: "",
    "k2-inf": true, units: "", method: "pde", tol: "1e-6", vmax: "0.0025", "fixed-vmax": false, samples: "100000",
    seed: "1", "use-material": false, R: "", "do-traction": true, "g-min": "2.3", "g-max": "5",
    "g-n": "200", "do-pdf": false, "pdf-g": "0.98", "pdf-k2": "5, 20, 110, 580, ∞", "grid-min": "",
    "grid-max": "", "grid-n": "", "do-sweep": false, vary: "m0",
    values: "0.1, 0.1468, 0.2154, 0.3162, 0.4642, 0.6813, 1, 1.468, 2.154, 3.162, 4.642, 6.813, 10",
  };
  const presets = {
    fig2: {
      note: "Fig. 2: the gap PDF at g̃ave = 0.98 for k̃2 = 5 by the paper's iteration, one curve per Vmax, each as computed at its Vmax (fixed_vmax; its error is 3 times the change at Vmax/2).",
      k2: "5", "k2-inf": false, method: "paper", tol: "0.1", vmax: "0.1, 0.05, 0.025, 0.0025", "fixed-vmax": true,
      "do-traction": false, "do-pdf": true, "pdf-k2": "5", "grid-min": "0.6", "grid-max": "1.6", "grid-n": "500",
    },
    fig3: {
      note: "Fig. 3: gap PDFs at g̃ave = 0.98 as the spectrum is cut at k̃2 = 5, 20, 110, 580 and ∞ (C = 1/(4π), k̃1 = 1, D = 2.5).",
      "do-traction": false, "do-pdf": true, "grid-min": "0.5", "grid-max": "1.8", "grid-n": "600",
    },
    fig4: {
      note: "Fig. 4: the modified force law for C = 1/(4π) (m̃0 = 0.5), k̃1 = 1, k̃2 = ∞, D = 2.5; expect g̃eq ≈ 2.6028, σ̄max/σ0 ≈ 0.10126, Δγeff/Δγ ≈ 0.2015.",
    },
    fig4printed: {
      note: "Fig. 4 with C = 1/π as printed in (17) (m̃0 = 2): g̃eq ≈ 5.68, outside the paper's axes — the reason the presets use C/4.",
      level: "0.318310", "g-min": "4.5", "g-max": "12",
    },
    fig5a: {
      note: "Fig. 5: Δγeff and σ̄max against m̃0 for D = 2.05, k̃1 = 0.5, k̃2 = ∞.",
      exp: "2.05", "level-kind": "m0", level: "1", k1: "0.5", "do-traction": false, "do-sweep": true, tol: "1e-4",
    },
    fig5b: {
      note: "Fig. 5: Δγeff and σ̄max against m̃0 for D = 2.5, k̃1 = 0.5, k̃2 = ∞.",
      exp: "2.5", "level-kind": "m0", level: "1", k1: "0.5", "do-traction": false, "do-sweep": true, tol: "1e-4",
    },
    fig6: {
      note: "Fig. 6: the statistical curve for the numerical model's surface (D = 2.2, k̃1 = 1, k̃2 = 8, m̃0 = 0.218), and the sweep over the three m̃0 of the figure.",
      exp: "2.2", "level-kind": "m0", level: "0.218", k2: "8", "k2-inf": false, "g-min": "1", "g-max": "4",
      "do-sweep": true, values: "0.1, 0.218, 0.3",
    },
  };

  function setForm(values) {
    for (const [id, v] of Object.entries(values)) {
      if (id === "note") continue;
      if (id === "kind") {
        document.querySelector(`input[name="kind"][value="${v}"]`).checked = true;
        continue;
      }
      const e = $(id);
      if (e.type === "checkbox") e.checked = v;
      else e.value = v;
    }
    unitsNow = $("units").value; /* a preset's values are in its own units */
    $("units-note").textContent = "";
    syncVisibility();
  }

  function applyPreset(name) {
    const p = presets[name];
    setForm({ ...defaults, ...p });
    $("preset-note").textContent = p.note;
    run();
  }

  /* ---- visibility of optional parts ---- */

  /* χ = 3ε²E* / (16Δγ) (theory.md (15)) of the form's material, in m; null when not a number. */
  function chiOf(m) {
    if (!m) return null;
    let E = m.E_star;
    if (E === undefined && [m.E1, m.nu1, m.E2, m.nu2].every((v) => typeof v === "number")) E = 1 / ((1 - m.nu1 * m.nu1) / m.E1 + (1 - m.nu2 * m.nu2) / m.E2);
    const chi = (3 * m.epsilon * m.epsilon * E) / (16 * m.dgamma);
    return Number.isFinite(chi) && chi > 0 ? chi : null;
  }

  /* SI mode: the fields say their units, k1 its minimum k0/χ, the sweep its variable's unit. */
  function syncUnits() {
    const si = $("units").value === "SI";
    const chi = chiOf(materialObject());
    const min = si ? (chi ? `> k0/χ = ${fmt(K0 / chi, 4)} 1/m` : "> k0/χ: give the material") : "> k̃0 ≈ 0.46978";
    $("k1-label").textContent = si ? `k1 (lower cut-off, 1/m, ${min})` : `k̃1 (lower cut-off, ${min})`;
    $("k2-label").textContent = si ? "k2 (upper cut-off, 1/m)" : "k̃2 (upper cut-off)";
    $("table-label").textContent = si
      ? "k (1/m), P (m⁴) per line (CSV; # comments and a header line are skipped; a third column is P_err)"
      : "k̃, P̃S per line (CSV; # comments and a header line are skipped; a third column is P_err)";
    const levels = si ? { C: "C (P = C k^(2D−8), m^(2D−4))", m0: "m0 (height variance, m²)", h_rms: "h_rms (m)" } : { C: "C (P̃S = C k̃^(2D−8))", m0: "m̃0 (height variance)", h_rms: "h_rms" };
    for (const o of $("level-kind").options) o.textContent = levels[o.value];
    const vary = si ? { m0: "m0 (m²)", C: "C (SI)", D: "D", k1: "k1 (1/m)" } : { m0: "m̃0", C: "C", D: "D", k1: "k̃1" };
    for (const o of $("vary").options) o.textContent = vary[o.value];
    const unit = si ? { m0: "m²", C: "m^(2D−4)", D: "", k1: "1/m" }[$("vary").value] : "";
    $("sweep-units").textContent = unit ? `(values in ${unit})` : "";
  }

  /* A converted value as the text of a field: 6 significant digits, no trailing zeros. */
  function numText(x) {
    const a = Math.abs(x);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) return x.toExponential(5).replace(/\.?0+e/, "e").replace("e+", "e");
    return String(Number(x.toPrecision(6)));
  }

  /* The PSD's D as the form gives it (D, or 3 − H); null when it is no number. */
  function formD() {
    const v = field("exp");
    if (typeof v !== "number") return null;
    return $("exp-kind").value === "H" ? 3 - v : v;
  }

  /* Switching "units of the PSD" converts every field in the PSD's units (api.md "Physical
   * units", core/units.c) with the material's χ and ε: k = k̃/χ, C = C̃ ε² χ^(2D−6), m0 = m̃0 ε²,
   * h_rms = h̃ ε, a table's P = P̃ ε² χ², and the sweep's values as its variable. Back again, a
   * field still holding the converted text gets its text from before (no rounding drift). The
   * gaps, the PDF's k̃2 list and the grids stay dimensionless (the server reads them so). */
  let lastConversion = null; /* {to, chi, eps, before: {id: text}, after: {id: text}} */
  function convertFields(toSI, opts = {}) {
    const m = materialObject();
    const chi = chiOf(m);
    const eps = m && typeof m.epsilon === "number" && m.epsilon > 0 ? m.epsilon : null;
    if (!chi || !eps) return null;
    const D = formD();
    const f = toSI ? 1 : -1; /* exponent of each scale: SI = dimensionless × scale^f */
    const scale = {
      k: Math.pow(chi, -f),
      m0: Math.pow(eps, 2 * f),
      h_rms: Math.pow(eps, f),
      C: D === null ? null : Math.pow(eps * eps * Math.pow(chi, 2 * D - 6), f),
      D: 1,
      P: Math.pow(eps * eps * chi * chi, f),
    };
    const kinds = [$("level-kind").value, $("vary").value, $("exp-kind").value, $("exp").value].join("|");
    const same = lastConversion && lastConversion.to === (toSI ? "" : "SI") && lastConversion.chi === chi && lastConversion.eps === eps && lastConversion.kinds === kinds;
    const before = {};
    const after = {};
    const skipped = [];
    const set = (id, compute) => {
      const old = $(id).value;
      let text;
      if (same && lastConversion.after[id] === old && lastConversion.before[id] !== undefined) text = lastConversion.before[id];
      else text = compute(old);
      if (text === null) return;
      before[id] = old;
      after[id] = text;
      $(id).value = text;
    };
    const one = (x, k) => {
      const v = val(x);
      if (typeof v !== "number") return null;
      if (scale[k] === null) {
        skipped.push(k);
        return null;
      }
      return numText(v * scale[k]);
    };
    set("k1", (t) => one(t, "k"));
    if (!$("k2-inf").checked) set("k2", (t) => one(t, "k"));
    set("level", (t) => one(t, $("level-kind").value));
    const vary = $("vary").value;
    set("values", (t) => {
      const xs = list(t);
      if (!xs.length || !xs.every((x) => typeof x === "number")) return null;
      if (vary === "C" && scale.C === null) return skipped.push("C"), null;
      const k = vary === "k1" ? "k" : vary;
      return xs.map((x) => numText(x * scale[k])).join(", ");
    });
    if (opts.table !== false) {
      set("table", (t) => {
        let q;
        try {
          q = parseTable(t);
        } catch (e) {
          return null;
        }
        const head = toSI ? `k [1/m], P [m^4]${q.P_err ? ", P_err [m^4]" : ""}` : `k̃, P̃S${q.P_err ? ", P̃S_err" : ""}`;
        const rows = q.k.map((k, i) => [k * scale.k, q.P[i] * scale.P, ...(q.P_err ? [q.P_err[i] * scale.P] : [])].map(numText).join(", "));
        return [`# converted ${toSI ? "to SI" : "to dimensionless"} with χ = ${numText(chi)} m, ε = ${numText(eps)} m`, head, ...rows].join("\n");
      });
    }
    lastConversion = { to: toSI ? "SI" : "", chi, eps, kinds, before, after };
    return { chi, eps, changed: Object.keys(after), skipped };
  }

  /* The "units of the PSD" select changed: SI needs the material (switched on), and the fields
   * in the PSD's units follow; a material whose numbers are not usable keeps the old units. */
  let unitsNow = "";
  function onUnits() {
    const toSI = $("units").value === "SI";
    if (toSI === (unitsNow === "SI")) return syncVisibility();
    if (toSI && !$("use-material").checked) $("use-material").checked = true;
    const done = convertFields(toSI);
    if (!done) {
      $("units").value = unitsNow;
      syncVisibility();
      showFieldError("units", "give the material's E*, Δγ and ε as numbers first: the fields are converted with its χ and ε");
      return;
    }
    unitsNow = $("units").value;
    syncVisibility();
    const names = { k1: "k1", k2: "k2", level: $("level-kind").value, values: "the sweep's values", table: "the table" };
    const what = done.changed.map((id) => names[id]).join(", ");
    const note = `${toSI ? "In SI" : "Dimensionless"} now${what ? `: ${what} converted with χ = ${numText(done.chi)} m, ε = ${numText(done.eps)} m` : ""}${done.skipped.length ? " (C not converted: D is no number)" : ""}; the gaps and the PDF's k̃2 stay dimensionless.`;
    $("units-note").textContent = note;
    try {
      showPsd(common(), null);
    } catch (e) {
      /* a table that does not parse: the picture waits */
    }
  }

  function syncVisibility() {
    syncUnits();
    const table = document.querySelector('input[name="kind"]:checked').value === "table";
    $("power-fields").hidden = table;
    $("table-fields").hidden = !table;
    $("k2").disabled = $("k2-inf").checked;
    $("vmax-field").hidden = $("method").value !== "paper";
    $("mc-field").hidden = $("method").value !== "montecarlo";
    $("material-fields").hidden = !$("use-material").checked;
    const pair = $("modulus-kind").value === "pair";
    $("pair-fields").hidden = !pair;
    $("estar-field").hidden = pair;
  }

  /* ---- simulation jobs (jobs.js): shown only when the server offers them ---- */

  /* A chart and its exports for a panel that jobs.js fills. */
  function showSeries(name, series, figOpts, answers) {
    const p = panels[name];
    p.series = series;
    p.xName = figOpts.xName || "x";
    p.answers = answers;
    const u = LJPlots.draw($(`plot-${name}`), { title: plotTitles[name], series, params: p.params, ...figOpts });
    updateExports();
    return u;
  }

  async function probeJobs() {
    let doc = null;
    try {
      doc = await (await fetch("/openapi.json")).json();
    } catch (e) {
      return; /* no OpenAPI document: no jobs form */
    }
    const op = (doc.paths || {})["/v1/simulations"];
    if (!op || !op.post || /planned/i.test(op.post.summary || "") || typeof LJJobs === "undefined") return;
    LJJobs.init({
      common, post, el, list, val, fmt, errFmt, clearErrors, showSeries,
      placeProblem, setIdle, focusFirstInvalid,
      claim: collectClaims,
      /* a simulation starts the panel afresh, unless it is kept beside the previous job */
      panel: (name, { keep, ...req }) => {
        if (req.endpoint === "simulations" && !keep) resetPanel(name);
        panels[name].requests.push(req);
      },
    });
  }

  /* ---- wiring ---- */

  function init() {
    collectClaims();
    for (const n of panelNames) resetPanel(n);
    addExports();
    $("form").addEventListener("submit", (ev) => {
      ev.preventDefault();
      $("preset-note").textContent = "";
      run();
    });
    for (const b of document.querySelectorAll("[data-preset]")) {
      b.addEventListener("click", () => applyPreset(b.dataset.preset));
    }
    $("cancel").addEventListener("click", () => abort && abort.abort());
    for (const id of ["k2-inf", "method", "use-material", "modulus-kind", "vary"]) $(id).addEventListener("change", syncVisibility);
    $("units").addEventListener("change", onUnits);
    for (const id of ["E_star", "E1", "nu1", "E2", "nu2", "dgamma", "epsilon"]) $(id).addEventListener("input", syncUnits);
    for (const r of document.querySelectorAll('input[name="kind"]')) r.addEventListener("change", syncVisibility);
    $("table-file").addEventListener("change", async () => {
      const f = $("table-file").files[0];
      if (f) $("table").value = await f.text();
    });
    for (const i of document.querySelectorAll("input, select, textarea")) {
      i.addEventListener("input", () => {
        i.classList.remove("invalid");
        i.removeAttribute("aria-invalid");
        const s = errorSpan(i.id);
        if (s) s.textContent = "";
      });
    }
    syncVisibility();
    try {
      showPsd(common(), null);
    } catch (e) {
      /* the picture waits for a usable form */
    }
    updateExports();
    probeJobs();
    if (typeof LJTopo !== "undefined") {
      LJTopo.init({
        panels, post, el, val, fmt, errFmt, clearErrors, placeProblem, showFieldError, showSeries,
        resetPanel, materialObject, summaryTable, metaLine, warnings, setBusy, setIdle, download,
        updateExports, emptyPanel, useSpectrum, focusFirstInvalid,
      });
    }
  }

  window.LJApp = { panels, run, applyPreset, panelCSV, panelJSON, panelCurl, fieldFor, requests: buildRequests, showProblem, describe };
  init();
})();

/* validity.js -- where the theory holds, on the page (issue 31).
 *
 * Every theory answer carries "model": the validity map's relative difference (theory −
 * discrete model)/discrete model of g̃eq, σ̄max and Δγeff for the request's D, m̃0 and k̃2/k̃1
 * (GET /v1/validity holds the whole map). LJValidity.line(model) is the one-line verdict each
 * result shows; LJValidity.draw(box, model) draws the map's D × m̃0 grid for the request's
 * k̃2/k̃1 level on the PSD card, each cell coloured by the largest |difference| of the three
 * (green within 5 %, amber to 20 %, red beyond) with Δγeff's in %, and a marker where the
 * request sits (hollow, at the nearest point, when it is off the map). The map is fetched once.
 * Everything is built with DOM calls (no inline style: the page's CSP is default-src 'self').
 */
(function () {
  "use strict";
  const SVG = "http://www.w3.org/2000/svg";
  let mapPromise = null;

  function getMap() {
    if (!mapPromise)
      mapPromise = fetch("/v1/validity", { headers: { Accept: "application/json" } })
        .then((r) => (r.ok ? r.json() : Promise.reject(new Error(`GET /v1/validity: ${r.status}`))))
        .catch((e) => {
          mapPromise = null; /* try again next time */
          throw e;
        });
    return mapPromise;
  }

  const pct = (x) => `${x >= 0 ? "+" : "−"}${Math.abs(100 * x).toFixed(Math.abs(x) < 0.1 ? 1 : 0)} %`;
  const worst = (v) => Math.max(Math.abs(v.g_eq), Math.abs(v.sigma_max), Math.abs(v.dgamma_eff));
  const ratio = (r) => (r === null ? "∞" : String(r));

  /* The verdict in one line (a div of class meta, or warn beyond 5 %). */
  function line(model) {
    const div = document.createElement("div");
    div.className = "meta validity-line";
    if (!model) return div;
    const v = model.vs_discrete;
    if (!v) {
      div.textContent = `model: not on the validity map (${model.reason || "no verdict"})`;
      return div;
    }
    const e = model.vs_discrete_err || {};
    const parts = `g̃eq ${pct(v.g_eq)}, σ̄max ${pct(v.sigma_max)}, Δγeff ${pct(v.dgamma_eff)} (± ${(100 * worst(e)).toFixed(1)} %)`;
    const w = worst(v);
    const where = model.inside
      ? `at D = ${model.D.toFixed(3)}, m̃0 = ${+model.m0.toPrecision(3)}, k̃2/k̃1 = ${ratio(model.k2_over_k1)}${model.bound ? " (m̃0 below the map: its values at the smallest m̃0, a bound)" : ""}`
      : `off the map (${model.reason}); nearest point D = ${model.at.D}, m̃0 = ${+model.at.m0.toPrecision(3)}, k̃2/k̃1 = ${ratio(model.at.k2_over_k1)}`;
    if (w > 0.05) {
      div.className = "warn validity-line";
      div.textContent = `⚠ model: the theory differs from the discrete model by ${parts} ${where}; a simulation job with k_split (the hybrid) gives a better number`;
    } else {
      div.textContent = `model: theory within ${(100 * w).toFixed(1)} % of the discrete model (${parts}) ${where}`;
    }
    return div;
  }

  /* A sweep's verdict: how many of its values the theory gets within 5 %, and the largest. */
  function sweepLine(results) {
    const div = document.createElement("div");
    div.className = "meta validity-line";
    const ms = (results || []).map((r) => r && r.model).filter((m) => m && m.vs_discrete);
    if (!ms.length) return div;
    const over = ms.filter((m) => worst(m.vs_discrete) > 0.05).length;
    const big = Math.max(...ms.map((m) => worst(m.vs_discrete)));
    const off = ms.filter((m) => !m.inside).length;
    if (over) div.className = "warn validity-line";
    div.textContent = `${over ? "⚠ " : ""}model: the theory is within 5 % of the discrete model at ${ms.length - over} of ${ms.length} values (largest difference ${(100 * big).toFixed(0)} %${off ? `; ${off} off the map, read at its nearest point` : ""})${over ? "; a simulation job with k_split (the hybrid) gives a better number" : ""}`;
    return div;
  }

  function svg(tag, attrs, text) {
    const n = document.createElementNS(SVG, tag);
    for (const [k, v] of Object.entries(attrs || {})) n.setAttribute(k, String(v));
    if (text !== undefined) n.textContent = text;
    return n;
  }

  const colour = (w) => (w <= 0.05 ? "#cfe8d2" : w <= 0.2 ? "#f6e2b3" : "#f3c1c1");

  /* Position of x on the axis a (increasing) in cell units: i at a[i], linear between. */
  function place(a, x) {
    if (x <= a[0]) return 0;
    for (let i = 0; i + 1 < a.length; i++) if (x <= a[i + 1]) return i + (x - a[i]) / (a[i + 1] - a[i]);
    return a.length - 1;
  }

  function render(box, map, model) {
    const levels = map.map.k2_over_k1;
    /* the level of the request: the nearest the map has (∞ is null and sorts last) */
    const want = model ? (model.at ? model.at.k2_over_k1 : model.k2_over_k1) : levels[0];
    const inv = (r) => (r === null ? 0 : 1 / r);
    let level = levels[0];
    for (const l of levels) if (Math.abs(inv(l) - inv(want)) < Math.abs(inv(level) - inv(want))) level = l;
    const Ds = map.map.D, ms = map.map.m0;
    const cell = {};
    for (const r of map.map.rows) if (r.k2_over_k1 === level) cell[`${r.D}|${r.m0}`] = r;
    const cw = 44, ch = 26, left = 44, top = 8, bottom = 34;
    const W = left + cw * ms.length + 8, H = top + ch * Ds.length + bottom;
    const s = svg("svg", { viewBox: `0 0 ${W} ${H}`, class: "validity-svg", role: "img",
      "aria-label": `validity map at k2/k1 = ${ratio(level)}: |theory − discrete| by D and m0` });
    Ds.forEach((D, i) => {
      const y = top + ch * (Ds.length - 1 - i);
      s.append(svg("text", { x: left - 6, y: y + ch / 2 + 4, "text-anchor": "end", class: "vm-axis" }, `D ${D}`));
      ms.forEach((m, j) => {
        const r = cell[`${D}|${m}`];
        const x = left + cw * j;
        const rect = svg("rect", { x, y, width: cw - 1, height: ch - 1, fill: r ? colour(worst(r.vs_discrete)) : "#eee" });
        if (r) rect.append(svg("title", {}, `D ${D}, m̃0 ${m}: g̃eq ${pct(r.vs_discrete.g_eq)}, σ̄max ${pct(r.vs_discrete.sigma_max)}, Δγeff ${pct(r.vs_discrete.dgamma_eff)}`));
        s.append(rect);
        if (r) s.append(svg("text", { x: x + cw / 2, y: y + ch / 2 + 4, "text-anchor": "middle", class: "vm-cell" }, `${Math.round(100 * r.vs_discrete.dgamma_eff)}`));
      });
    });
    ms.forEach((m, j) => s.append(svg("text", { x: left + cw * j + cw / 2, y: top + ch * Ds.length + 13, "text-anchor": "middle", class: "vm-axis" }, String(m))));
    s.append(svg("text", { x: left + (cw * ms.length) / 2, y: H - 4, "text-anchor": "middle", class: "vm-axis" }, `m̃0 · k̃2/k̃1 = ${ratio(level)} · numbers: Δγeff, theory vs discrete, %`));
    if (model && model.at) {
      const lm = ms.map(Math.log);
      const px = left + cw * (place(lm, Math.log(model.at.m0)) + 0.5);
      const py = top + ch * (Ds.length - 1 - place(Ds, model.at.D) + 0.5);
      s.append(svg("circle", { cx: px, cy: py, r: 12, class: model.inside ? "vm-marker" : "vm-marker vm-off", id: "validity-marker" }));
    }
    const caption = document.createElement("div");
    caption.className = "meta";
    caption.textContent = model
      ? model.inside
        ? `◯ this request (D = ${model.D.toFixed(3)}, m̃0 = ${+model.m0.toPrecision(3)}, k̃2/k̃1 = ${ratio(model.k2_over_k1)}) on the validity map. Colour: the largest difference of g̃eq, σ̄max, Δγeff: green within 5 %, amber to 20 %, red beyond`
        : `◌ off the map: ${model.reason}; marked (dashed) at the nearest point`
      : "the validity map (GET /v1/validity); compute to see where the request sits";
    box.replaceChildren(s, caption);
  }

  /* Draws the map with the request's model into box (empties it when the map cannot be had). */
  function draw(box, model) {
    if (!box) return Promise.resolve();
    return getMap()
      .then((map) => render(box, map, model))
      .catch((e) => {
        box.textContent = `validity map unavailable: ${e.message}`;
      });
  }

  window.LJValidity = { line, sweepLine, draw, getMap };
})();

/* jobs.js -- numerical-model jobs (docs/api.md "simulations"): POST /v1/simulations answers 202 with
 * {id, status, progress, elapsed_ms}; GET /v1/simulations/ID is polled for progress until the
 * status is done (then "result" holds g_ave[], sigma[], error.sigma[], …), failed or cancelled
 * (then "problem"); DELETE cancels. app.js calls LJJobs.init(api) when /openapi.json lists the
 * endpoint; until then the card stays hidden. The finished run is plotted against the
 * statistical curve of the same PSD (POST /v1/traction over the simulated range), as in Fig. 6.
 */
"use strict";

const LJJobs = (() => {
  const $ = (id) => document.getElementById(id);
  const POLL_MS = 500;
  let api = null; /* LJApp's helpers: common(), post(), el(), problems */
  let current = null; /* {id, timer} */

  function input(id, label, value, ptr) {
    return api.el(
      "div",
      { class: "field" },
      api.el("label", { for: id }, label),
      api.el("input", { id, type: "text", value, "data-ptr": ptr, "data-panel": "jobs" }),
      api.el("span", { class: "err", "data-for": id })
    );
  }

  function build() {
    const box = $("jobs-fields");
    box.replaceChildren(
      input("sim-L", "L̃ (side of the square; empty: 2π/k̃1)", "", "/L"),
      input("sim-n", "n (grid points per side, even)", "64", "/n"),
      input("sim-real", "realizations", "4", "/realizations"),
      input("sim-seed", "seed", "1", "/seed"),
      input("sim-g", "mean gaps g̃ave (list)", "1.2, 1.5, 2, 2.5, 3, 4", "/g_ave"),
      api.el(
        "div",
        { class: "actions" },
        api.el("button", { type: "button", id: "sim-start", class: "primary" }, "Start simulation"),
        " ",
        api.el("button", { type: "button", id: "sim-cancel", disabled: "" }, "Cancel job")
      ),
      api.el("progress", { id: "sim-progress", class: "jobbar", max: "1", value: "0" }),
      api.el("div", { id: "sim-state", class: "meta" }, "No job.")
    );
    api.claim(box);
    $("sim-start").addEventListener("click", start);
    $("sim-cancel").addEventListener("click", cancel);
  }

  function request() {
    const c = api.common();
    const body = { psd: c.psd, g_ave: api.list($("sim-g").value) };
    if (c.material) body.material = c.material;
    for (const [id, key] of [["sim-L", "L"], ["sim-n", "n"], ["sim-real", "realizations"], ["sim-seed", "seed"]]) {
      const v = api.val($(id).value);
      if (v !== undefined) body[key] = v;
    }
    return body;
  }

  function state(s) {
    $("sim-progress").value = s.progress || 0;
    $("sim-state").dataset.status = s.status;
    $("sim-state").textContent = `job ${s.id.slice(0, 8)}…: ${s.status}, ${Math.round(100 * (s.progress || 0))} %, ${api.fmt(s.elapsed_ms / 1000, 3)} s`;
  }

  /* The submission was answered with a problem: beside the fields, and in the job's line. */
  function refused(status, json) {
    const loose = api.placeProblem(json, "jobs");
    $("sim-state").textContent = `${status} ${json.title || ""}: ${[json.detail, ...loose].filter(Boolean).join("; ")}`;
    $("sim-state").dataset.status = "refused";
  }

  async function start() {
    if (current) return;
    api.clearErrors();
    const body = request();
    const text = JSON.stringify(body);
    api.panel("jobs", { endpoint: "simulations", text });
    const r = await fetch("/v1/simulations", { method: "POST", headers: { "Content-Type": "application/json" }, body: text });
    const json = await r.json().catch(() => ({}));
    if (r.status !== 202) {
      refused(r.status, json);
      return;
    }
    current = { id: json.id };
    $("sim-start").disabled = true;
    $("sim-cancel").disabled = false;
    state(json);
    poll(body);
  }

  async function poll(body) {
    if (!current) return;
    const r = await fetch(`/v1/simulations/${current.id}`);
    const s = await r.json().catch(() => ({}));
    if (r.status !== 200) {
      finish(`${r.status} ${s.title || ""}: ${s.detail || ""}`);
      return;
    }
    state(s);
    if (s.status === "queued" || s.status === "running") {
      current.timer = setTimeout(() => poll(body), POLL_MS);
      return;
    }
    if (s.status === "done") {
      await show(body, s.result);
      finish(`done in ${api.fmt(s.elapsed_ms / 1000, 3)} s`);
    } else {
      const p = s.problem || {};
      finish(`${s.status}: ${p.detail || p.title || ""}`);
    }
  }

  function finish(text) {
    if (current && current.timer) clearTimeout(current.timer);
    current = null;
    $("sim-start").disabled = false;
    $("sim-cancel").disabled = true;
    $("sim-state").textContent += ` — ${text}`;
  }

  async function cancel() {
    if (!current) return;
    const id = current.id;
    clearTimeout(current.timer);
    const r = await fetch(`/v1/simulations/${id}`, { method: "DELETE" });
    const s = await r.json().catch(() => ({}));
    if (s.id) state(s);
    finish("cancelled");
  }

  /* The numerical curve with its error bars' half-widths, beside the theory at the same gaps. */
  async function show(body, res) {
    /* the theory as a smooth curve over the simulated range */
    const lo = Math.min(...res.g_ave);
    const hi = Math.max(...res.g_ave);
    const theoryReq = { psd: body.psd, g_ave: hi > lo ? { min: lo, max: hi, n: 100 } : [lo] };
    if (body.material) theoryReq.material = body.material;
    const text = JSON.stringify(theoryReq);
    api.panel("jobs", { endpoint: "traction", text });
    const t = await api.post("traction", text);
    const series = [
      { name: "σ̄/σ0 numerical model", x: res.g_ave, y: res.sigma, err: res.error && res.error.sigma, color: "#d1495b", points: true },
    ];
    if (t.status === 200) series.push({ name: "σ̄/σ0 statistical theory", x: t.json.g_ave, y: t.json.sigma, err: t.json.error.sigma, color: "#1f5fbf" });
    api.showSeries("jobs", series, { xLabel: "g̃ave", xName: "g̃ave", yLabel: "σ̄/σ0" }, [res, t.json]);
    const worst = Math.max(...((res.error && res.error.sigma) || [0]).map(Math.abs));
    $("readout-jobs").replaceChildren(
      api.el("div", {}, `${res.g_ave.length} mean gaps, ${res.realizations} realization(s) on ${res.n}×${res.n}, L̃ = ${api.fmt(res.L)}; m̃0 = ${api.fmt(res.m0)} (grid ${api.fmt(res.m0_grid)})`),
      api.el("div", { class: "meta" }, `largest standard error of σ̄ ${api.errFmt(worst)}; run ${api.fmt(res.elapsed_ms, 3)} ms`)
    );
  }

  function init(helpers) {
    api = helpers;
    $("jobs-card").hidden = false;
    $("card-jobs").hidden = false;
    build();
  }

  return { init, request, refused };
})();

/* jobs.js -- numerical-model jobs (docs/api.md "simulations"): POST /v1/simulations answers 202 with
 * {id, status, progress, elapsed_ms}; GET /v1/simulations/ID is polled for progress until the
 * status is done (then "result" holds g_ave[], sigma[], error.sigma[], …), failed or cancelled
 * (then "problem"); DELETE cancels. app.js calls LJJobs.init(api) when /openapi.json lists the
 * endpoint; until then the card stays hidden. A job kept over a reload that the server no longer
 * knows (404: restarted with another state directory) is forgotten with one calm line.
 *
 * With k̃split the job is the hybrid (the grid carries [k̃1, k̃split], the finer band acts through
 * the statistical theory); "also the full model" then queues a second job without k̃split on its
 * own grid, after the first. The finished runs are plotted against the statistical curve of the
 * same PSD (POST /v1/traction over the simulated range), as in Fig. 6: theory, hybrid and, when
 * run, the full model, with the largest |hybrid − full| and the time ratio in the readout.
 */
"use strict";

const LJJobs = (() => {
  const $ = (id) => document.getElementById(id);
  const POLL_MS = 500;
  let api = null; /* LJApp's helpers: common(), post(), el(), problems */
  let current = null; /* {id, timer, cancelled} */

  function input(id, label, value, ptr) {
    const attrs = { id, type: "text", value, "data-panel": "jobs" };
    if (ptr) attrs["data-ptr"] = ptr;
    return api.el(
      "div",
      { class: "field" },
      api.el("label", { for: id }, label),
      api.el("input", attrs),
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
      input("sim-k2", "k̃2 of the simulated surface when the PSD's is ∞ (the grid needs a band-limited spectrum; Fig. 6: 8)", "8", "/psd/k2"),
      input("sim-ksplit", "k̃split (hybrid: the grid carries [k̃1, k̃split], the finer band acts through the theory; empty: the full model)", "", "/k_split"),
      api.el(
        "div",
        { class: "field", id: "sim-full-field" },
        api.el("label", { for: "sim-full", class: "inline" }, api.el("input", { id: "sim-full", type: "checkbox" }), " also run the full model, on n ="),
        api.el("input", { id: "sim-nfull", type: "text", value: "128", "aria-label": "n of the full model" }),
        api.el("span", { class: "err", "data-for": "sim-nfull" })
      ),
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
    $("sim-ksplit").addEventListener("input", sync);
    sync();
  }

  function sync() {
    $("sim-full-field").hidden = api.val($("sim-ksplit").value) === undefined;
  }

  /* The job's body, and the full model's beside a hybrid when asked (null otherwise). */
  function requests() {
    const c = api.common();
    const body = { psd: { ...c.psd }, g_ave: api.list($("sim-g").value) };
    /* the form's k̃2 = ∞ is no band: the job takes the card's own finite k̃2 (the defaults run) */
    if (body.psd.kind === "power" && (body.psd.k2 === undefined || body.psd.k2 === null) && api.val($("sim-k2").value) !== undefined) body.psd.k2 = api.val($("sim-k2").value);
    if (c.units) body.units = c.units;
    if (c.material) body.material = c.material;
    for (const [id, key] of [["sim-L", "L"], ["sim-n", "n"], ["sim-real", "realizations"], ["sim-seed", "seed"], ["sim-ksplit", "k_split"]]) {
      const v = api.val($(id).value);
      if (v !== undefined) body[key] = v;
    }
    let full = null;
    if (body.k_split !== undefined && $("sim-full").checked) {
      full = { ...body };
      delete full.k_split;
      const n = api.val($("sim-nfull").value);
      if (n !== undefined) full.n = n;
      else delete full.n;
    }
    return { body, full };
  }

  /* The job's body (the first job's, for a hybrid with the full model beside it). */
  function request() {
    return requests().body;
  }

  /* The submission was answered with a problem: beside the fields, and in the job's line. */
  function refused(status, json) {
    const loose = api.placeProblem(json, "jobs");
    $("sim-state").textContent = `${status} ${json.title || ""}: ${[json.detail, ...loose].filter(Boolean).join("; ")}`;
    $("sim-state").dataset.status = "refused";
    /* the header and the view say it too: the field that was refused, else the job's line */
    const bad = api.focusFirstInvalid ? api.focusFirstInvalid() : null;
    if (!bad) $("sim-state").scrollIntoView({ block: "center" });
    if (api.setIdle) api.setIdle(`The simulation was refused (${status}): ${bad ? "see the highlighted field" : "see the simulation card"}.`, true);
  }

  function state(s, what) {
    $("sim-progress").value = s.progress || 0;
    $("sim-state").dataset.status = s.status;
    $("sim-state").textContent = `${what} job ${s.id.slice(0, 8)}…: ${s.status}, ${Math.round(100 * (s.progress || 0))} %, ${api.fmt(s.elapsed_ms / 1000, 3)} s`;
  }

  const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

  /* Submits one job and polls it to its end: {result} when done, else {text} saying why not. */
  async function runJob(body, what, first) {
    const text = JSON.stringify(body);
    api.panel("jobs", { endpoint: "simulations", text, keep: !first });
    const r = await fetch("/v1/simulations", { method: "POST", headers: { "Content-Type": "application/json" }, body: text });
    const json = await r.json().catch(() => ({}));
    if (r.status !== 202) {
      if (first) {
        refused(r.status, json);
        return { refused: true };
      }
      const loose = (json.errors || []).map((e) => `${e.pointer}: ${e.detail}`);
      return { text: `${what}: ${r.status} ${json.title || ""}: ${[json.detail, ...loose].filter(Boolean).join("; ")}` };
    }
    current = { id: json.id, cancelled: false, what };
    remember({ id: json.id, what, body });
    state(json, what);
    return poll(what);
  }

  /* The running job in the URL's #job= and in localStorage: a reload finds it again. */
  const KEY = "ljgap-job";
  function remember(job) {
    try {
      if (job) localStorage.setItem(KEY, JSON.stringify(job));
      else localStorage.removeItem(KEY);
    } catch (e) {
      /* storage refused: the job is not kept over a reload */
    }
    history.replaceState(null, "", job ? `#job=${job.id}` : location.pathname + location.search);
  }

  /* Polls the current job to its end: as runJob answers. */
  async function poll(what) {
    for (;;) {
      await sleep(POLL_MS);
      if (current.cancelled) {
        remember(null);
        return { text: "" };
      }
      const g = await fetch(`/v1/simulations/${current.id}`);
      const s = await g.json().catch(() => ({}));
      if (g.status !== 200) {
        remember(null);
        /* 404: the server does not know the job (restarted with another state directory) */
        if (g.status === 404) return { gone: true, text: "" };
        return { text: `${g.status} ${s.title || ""}: ${s.detail || ""}` };
      }
      state(s, what);
      if (s.status === "done") {
        remember(null);
        return { result: s.result, elapsed: s.elapsed_ms };
      }
      if (s.status !== "queued" && s.status !== "running") {
        remember(null);
        const p = s.problem || {};
        return { text: p.detail || p.title || "" };
      }
    }
  }

  async function start() {
    if (current) return;
    api.clearErrors();
    const { body, full } = requests();
    $("sim-start").disabled = true;
    $("sim-cancel").disabled = false;
    const hybrid = body.k_split !== undefined;
    const a = await runJob(body, hybrid ? "hybrid" : "numerical", true);
    let b = null;
    if (a.result && full) b = await runJob(full, "full model", false);
    const runs = [];
    if (a.result) runs.push({ res: a.result, body, hybrid });
    if (b && b.result) runs.push({ res: b.result, body: full, hybrid: false });
    if (runs.length) await show(body, runs);
    const elapsed = [a, b].filter((x) => x && x.result).map((x) => `${api.fmt(x.elapsed / 1000, 3)} s`);
    const failed = [a, b].filter((x) => x && !x.result).map((x) => x.text);
    finish(a.refused ? null : failed.length ? failed.join("; ") : `done in ${elapsed.join(" + ")}`);
  }

  /* The buttons back; text (unless null: a refusal already said why) after the job's line. */
  function finish(text) {
    current = null;
    $("sim-start").disabled = false;
    $("sim-cancel").disabled = true;
    /* "done in 3.1 s" replaces the last poll's "done, 100 %, 3.1 s" rather than repeating it */
    if (text) $("sim-state").textContent = $("sim-state").textContent.replace(/: (done|cancelled|failed), \d+ %, [^,]*$/, ": $1") + ` — ${text}`;
  }

  async function cancel() {
    if (!current) return;
    current.cancelled = true;
    const r = await fetch(`/v1/simulations/${current.id}`, { method: "DELETE" });
    const s = await r.json().catch(() => ({}));
    if (s.id) state(s, current ? current.what : "numerical"); /* its status says cancelled (or done, when it had ended) */
  }

  /* The runs with their error bars' half-widths, beside the theory over the same range. */
  async function show(body, runs) {
    const all = runs.flatMap((r) => r.res.g_ave);
    const lo = Math.min(...all);
    const hi = Math.max(...all);
    const theoryReq = { psd: body.psd, g_ave: hi > lo ? { min: lo, max: hi, n: 100 } : [lo] };
    if (body.material) theoryReq.material = body.material;
    const text = JSON.stringify(theoryReq);
    api.panel("jobs", { endpoint: "traction", text });
    const t = await api.post("traction", text);
    const series = runs.map((r) => ({
      name: r.hybrid ? `σ̄/σ0 hybrid (k̃split = ${api.fmt(r.res.k_split)})` : "σ̄/σ0 numerical model",
      x: r.res.g_ave,
      y: r.res.sigma,
      err: r.res.error && r.res.error.sigma,
      color: r.hybrid ? "#2a9d5c" : "#d1495b",
      points: true,
    }));
    if (t.status === 200) series.push({ name: "σ̄/σ0 statistical theory", x: t.json.g_ave, y: t.json.sigma, err: t.json.error.sigma, color: "#1f5fbf" });
    api.showSeries("jobs", series, { xLabel: "g̃ave", xName: "g̃ave", yLabel: "σ̄/σ0" }, [...runs.map((r) => r.res), t.json]);
    const lines = runs.map((r) => {
      const res = r.res;
      const worst = Math.max(...((res.error && res.error.sigma) || [0]).map(Math.abs));
      const head = `${r.hybrid ? "hybrid" : "numerical model"}: ${res.g_ave.length} mean gaps, ${res.realizations} realization(s) on ${res.n}×${res.n}, L̃ = ${api.fmt(res.L)}; m̃0 = ${api.fmt(res.m0)} (grid ${api.fmt(res.m0_grid)}); largest error of σ̄ ${api.errFmt(worst)}; run ${api.fmt(res.elapsed_ms, 3)} ms`;
      const out = [api.el("div", {}, head)];
      if (r.hybrid && res.fine) {
        const f = res.fine;
        const e = f.error || {};
        out.push(
          api.el(
            "div",
            { class: "meta", id: "readout-fine" },
            `fine band (k̃split, k̃2]: m̃0 = ${api.fmt(f.m0)}; its modified law: g̃eq = ${api.fmt(f.g_eq)} ± ${api.errFmt(e.g_eq)}, σ̄max/σ0 = ${api.fmt(f.sigma_max)} ± ${api.errFmt(e.sigma_max)}, Δγeff/Δγ = ${api.fmt(f.dgamma_eff)} ± ${api.errFmt(e.dgamma_eff)} (law tabulated to ${api.errFmt(f.law_error)})`
          )
        );
      }
      return out;
    });
    const hyb = runs.find((r) => r.hybrid);
    const full = runs.find((r) => !r.hybrid);
    if (hyb && full) {
      let d = -1;
      let at = null;
      hyb.res.g_ave.forEach((g, i) => {
        const j = full.res.g_ave.indexOf(g);
        if (j >= 0 && Math.abs(hyb.res.sigma[i] - full.res.sigma[j]) > d) {
          d = Math.abs(hyb.res.sigma[i] - full.res.sigma[j]);
          at = g;
        }
      });
      lines.push([
        api.el(
          "div",
          { class: "meta", id: "readout-compare" },
          `largest |hybrid − full| = ${api.fmt(d, 3)} σ0 at g̃ave = ${api.fmt(at)}; run times: hybrid ${api.fmt(hyb.res.elapsed_ms, 3)} ms, full model ${api.fmt(full.res.elapsed_ms, 3)} ms (full/hybrid = ${api.fmt(full.res.elapsed_ms / hyb.res.elapsed_ms, 3)})`
        ),
      ]);
    }
    $("readout-jobs").replaceChildren(...lines.flat());
  }

  /* After a reload: the job of the URL (#job=ID) or of localStorage, followed to its end. */
  async function resume() {
    let job = null;
    try {
      job = JSON.parse(localStorage.getItem(KEY) || "null");
    } catch (e) {
      job = null;
    }
    const m = location.hash.match(/job=([0-9a-f]+)/);
    if (m && (!job || job.id !== m[1])) job = { id: m[1], what: "numerical", body: null };
    if (!job || current) return;
    current = { id: job.id, cancelled: false, what: `${job.what} (resumed)` };
    $("sim-start").disabled = true;
    $("sim-cancel").disabled = false;
    $("sim-state").textContent = `job ${job.id.slice(0, 8)}… (from before the reload): asking…`;
    const a = await poll(`${job.what} (resumed)`);
    if (a.gone) {
      /* a job of another server (or a purged one): forgotten, said once, calmly */
      current = null;
      $("sim-start").disabled = false;
      $("sim-cancel").disabled = true;
      $("sim-progress").value = 0;
      $("sim-state").dataset.status = "gone";
      $("sim-state").textContent = `The job ${job.id.slice(0, 8)}… from before the reload is no longer known to the server (it may have been restarted); start it again if you need it.`;
      return;
    }
    if (a.result && job.body) await show(job.body, [{ res: a.result, body: job.body, hybrid: job.body.k_split !== undefined }]);
    finish(a.result ? `done in ${api.fmt(a.elapsed / 1000, 3)} s` : a.text);
  }

  function init(helpers) {
    api = helpers;
    $("jobs-card").hidden = false;
    $("card-jobs").hidden = false;
    build();
    resume();
  }

  return { init, request, refused };
})();

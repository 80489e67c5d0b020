// page.test.js -- the page in web/ in headless Debian chromium (playwright-core, no downloaded
// browser), against build/ljgapd (or $BUILD/ljgapd) on a port the kernel picks, serving the copy
// of the page compiled into it (no --web).
//   node --test tests/web/page.test.js            (from the repository root; BUILD=... to choose)
// Checks: the page loads under its Content-Security-Policy with the vendored uPlot; presets draw
// (canvas pixels inked, readouts filled, numbers against theory.md §4's reference values); hover
// readouts; a 422 problem lands beside the field its pointer names; exports (CSV, JSON, PNG,
// "copy as curl" re-run with curl gives the same numbers); a measured topography: upload, its PSD
// and fit, k1/k2 picked on the plot, the adhesion of the spectrum; several maps combined (each
// one's PSD sent as its psd object, the combination with its error band, its CSV; with a material
// the combine's domain and the adhesion of its psd object, as is and cut to k1, k2); not a single console error
// (the icon included); no request leaves the local server. Leaves screenshots in
// $BUILD/web-screenshot*.png.
// Chromium logs every 4xx answer the page fetches as a console error ("Failed to load
// resource"), however the page handles it. So the two older tests of problems beside their fields
// take the server's real 422 for the exact request the page builds from the form, fetched here
// outside the browser, and hand it to the page's own display code (LJApp.showProblem,
// LJJobs.refused). Issue 30's test of a bad field lets the page fetch its 422 itself inside
// expect4xx(), which files that console line as intended; any other console error still fails.
// Issue 30's flows: a height map through "Use this spectrum" to traction, PDF and pull-off (one
// map and a combination); a binary file in one line; nothing stale after a preset; a bad field
// gets the view and the focus; the default simulation starts (202) and is found after a reload;
// no sideways scrolling at 390 px; the traction CSV is the server's, with units and the summary;
// the PNG at 2x; SI labels and plots; SI mode with the defaults (the fields converted, every
// request 200, the sweep on an SI axis, back to the same texts); the topography card's "computed
// for" line marked when its inputs change; a bogus #job= after a reload forgotten quietly (its
// 404, which Chromium logs, filed as intended like the 422s).
"use strict";

const { test, before, after } = require("node:test");
const assert = require("node:assert/strict");
const { spawn, execFileSync } = require("node:child_process");
const fs = require("node:fs");
const os = require("node:os");
const path = require("node:path");

const ROOT = path.resolve(__dirname, "../..");
const BUILD = path.resolve(ROOT, process.env.BUILD || "build");
const CHROMIUM = process.env.CHROMIUM || "/usr/bin/chromium";
const { chromium } = require(path.join(ROOT, "web/node_modules/playwright-core"));

let daemon;
let origin;
let ctx;
let page;
let userDir;
let stateDir; // the daemon's job store, removed at the end
const consoleErrors = [];
const intended = []; // 4xx answers a test provoked on purpose (see expect4xx)
let allow4xx = false;
/* Runs fn while the page may log its fetches' 4xx answers (a test of a refusal): any other
 * console error still fails the last test. */
async function expect4xx(fn) {
  allow4xx = true;
  try {
    return await fn();
  } finally {
    allow4xx = false;
  }
}
const requests = [];
const foreign = [];

function startDaemon() {
  return new Promise((resolve, reject) => {
    const bin = path.join(BUILD, "ljgapd");
    stateDir = fs.mkdtempSync(path.join(os.tmpdir(), "ljgap-web-state-"));
    daemon = spawn(bin, ["--port", "0", "--state-dir", stateDir],
      { cwd: os.tmpdir(), stdio: ["ignore", "pipe", "pipe"] });
    let out = "";
    const timer = setTimeout(() => reject(new Error(`${bin} did not say where it listens`)), 10000);
    daemon.stdout.on("data", (d) => {
      out += d;
      const m = out.match(/^listening on (http:\/\/127\.0\.0\.1:\d+)\//m);
      if (m) {
        clearTimeout(timer);
        resolve(m[1]);
      }
    });
    daemon.stderr.resume();
    daemon.on("error", reject);
  });
}

before(async () => {
  origin = await startDaemon();
  userDir = fs.mkdtempSync(path.join(os.tmpdir(), "ljgap-web-"));
  ctx = await chromium.launchPersistentContext(userDir, {
    executablePath: CHROMIUM,
    headless: true,
    acceptDownloads: true,
    viewport: { width: 1400, height: 1000 },
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
      "--disable-background-networking", "--disable-component-update", "--disable-sync"],
  });
  await ctx.grantPermissions(["clipboard-read", "clipboard-write"], { origin });
  // Every request of the page must go to the local server; anything else is recorded and refused.
  await ctx.route("**/*", (route) => {
    const url = route.request().url();
    requests.push(url);
    if (new URL(url).origin === origin || url.startsWith("blob:") || url.startsWith("data:")) return route.continue();
    foreign.push(url);
    return route.abort();
  });
  page = ctx.pages()[0] || (await ctx.newPage());
  page.on("console", (m) => {
    if (m.type() !== "error") return;
    const t = m.text();
    if (allow4xx && /^Failed to load resource: the server responded with a status of 4\d\d/.test(t)) return intended.push(t);
    consoleErrors.push(t);
  });
  page.on("pageerror", (e) => consoleErrors.push(String(e)));
  await page.addInitScript(() => {
    window.__csp = [];
    document.addEventListener("securitypolicyviolation", (e) => window.__csp.push(e.violatedDirective));
  });
  await page.goto(`${origin}/`);
});

after(async () => {
  if (ctx) await ctx.close();
  if (daemon) daemon.kill("SIGTERM");
  if (userDir) fs.rmSync(userDir, { recursive: true, force: true });
  if (stateDir) fs.rmSync(stateDir, { recursive: true, force: true });
});

/* Click a preset (or Compute) and wait until the status line says the run ended. */
async function runAndWait(selector) {
  await page.click(selector);
  await page.waitForFunction(() => {
    const s = document.getElementById("status-text").textContent;
    return document.getElementById("busy").hidden && !/^Ready/.test(s);
  }, null, { timeout: 60000 });
  return page.textContent("#status-text");
}

const inked = (id) => page.evaluate((i) => LJPlots.inked(document.getElementById(i)), id);
const num = (s) => Number(String(s).trim());

test("the page loads under default-src 'self' with the vendored uPlot", async () => {
  const csp = await page.getAttribute('meta[http-equiv="Content-Security-Policy"]', "content");
  assert.match(csp, /default-src 'self'/);
  assert.equal(await page.evaluate(() => typeof uPlot), "function");
  assert.equal(await page.evaluate(() => document.querySelectorAll("[data-preset]").length), 7);
  // the PSD of the default form is drawn before any request
  assert.ok((await inked("plot-psd")) > 200, "PSD canvas is blank");
});

test("Fig. 4 preset: traction curve, g_eq and sigma_max marked, readouts match theory.md §4", async () => {
  const status = await runAndWait('[data-preset="fig4"]');
  assert.match(status, /^Done/);
  const cells = await page.$$eval("#readout-traction table tr", (rows) =>
    rows.map((r) => [...r.children].map((c) => c.textContent)));
  const byName = Object.fromEntries(cells.map((r) => [r[0], r.slice(1)]));
  // theory.md §4 (two discretisations and Monte Carlo): g_eq 2.6028, sigma_max 0.10126 at 3.059
  assert.ok(Math.abs(num(byName["g̃eq"][0]) - 2.6028) < 2e-4, `g_eq ${byName["g̃eq"][0]}`);
  assert.ok(Math.abs(num(byName["σ̄max/σ0"][0]) - 0.10126) < 2e-5);
  assert.ok(Math.abs(num(byName["at g̃ave"][0]) - 3.059) < 2e-3);
  assert.ok(Math.abs(num(byName["Δγeff/Δγ"][0]) - 0.2015) < 5e-4);
  assert.match(byName["g̃eq"][1], /^± \d\.\de-\d+$/, "error estimate shown");
  assert.match(await page.textContent("#readout-traction"), /method pde · [\d.]+ ms/);
  assert.ok((await inked("plot-traction")) > 2000, "traction canvas is blank");
  assert.ok((await inked("plot-psd")) > 200, "PSD canvas is blank");
  const fig = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-traction")));
  assert.equal(fig.series.length, 3);
  assert.equal(fig.series[0].x.length, 200);
  assert.deepEqual(fig.marks.map((m) => m.type), ["vline", "point"]);
  // hover: uPlot's legend reads out every series at the cursor
  const box = await page.locator("#plot-traction .u-over").boundingBox();
  await page.mouse.move(box.x + box.width * 0.5, box.y + box.height * 0.5);
  const values = await page.$$eval("#plot-traction .u-legend .u-value", (v) => v.map((e) => e.textContent));
  assert.ok(values.length >= 3 && values.slice(0, 3).every((v) => Number.isFinite(Number(v))), `legend ${values}`);
});

test("issue 31: each answer's model line, and the validity map with the request on the PSD card", async () => {
  await runAndWait('[data-preset="fig4"]'); /* m0 = 0.5: the theory is far from the discrete model */
  const warn = await page.textContent("#readout-traction .validity-line");
  assert.match(warn, /^⚠ model: the theory differs from the discrete model by .*k_split/, warn);
  const map = await (await fetch(`${origin}/v1/validity`)).json();
  await page.waitForSelector("#validity-map svg #validity-marker");
  assert.equal(await page.$$eval("#validity-map svg rect", (r) => r.length), map.map.D.length * map.map.m0.length);
  /* the marker sits in the cell of D = 2.5, m0 = 0.5 (the preset is a point of the map's grid) */
  const inCell = await page.evaluate(() => {
    const m = document.getElementById("validity-marker").getBoundingClientRect();
    const cx = (m.left + m.right) / 2, cy = (m.top + m.bottom) / 2;
    const hit = [...document.querySelectorAll("#validity-map rect")].find((r) => {
      const b = r.getBoundingClientRect();
      return cx >= b.left && cx <= b.right && cy >= b.top && cy <= b.bottom;
    });
    return hit && hit.querySelector("title").textContent;
  });
  assert.match(inCell || "", /^D 2\.5, m̃0 0\.5:/);
  await page.locator("#card-psd").screenshot({ path: path.join(BUILD, "web-screenshot-validity.png") });
  /* inside the 5 % zone: the line says within, no warning */
  await page.selectOption("#level-kind", "m0");
  await page.fill("#level", "0.01");
  await page.uncheck("#k2-inf");
  await page.fill("#k2", "8");
  await page.uncheck("#do-pdf");
  await page.uncheck("#do-sweep");
  await runAndWait("#compute");
  const ok = await page.textContent("#readout-traction .validity-line");
  assert.match(ok, /^model: theory within \d\.\d % of the discrete model/, ok);
  assert.equal(await page.$$eval("#readout-traction .warn", (w) => w.length), 0);
  await page.setViewportSize({ width: 390, height: 844 });
  const box = await page.evaluate(() => document.querySelector("#validity-map svg").getBoundingClientRect().right);
  assert.ok(box <= 390, `the map ends at ${box} px at 390`);
  await page.setViewportSize({ width: 1400, height: 1000 });
  await page.check("#k2-inf");
  await page.check("#do-pdf");
  await page.check("#do-sweep");
  await page.selectOption("#level-kind", "C");
});

test("Fig. 3 preset: five gap PDFs, unit mass, peaks of theory.md §4", async () => {
  assert.match(await runAndWait('[data-preset="fig3"]'), /^Done/);
  assert.ok((await inked("plot-pdf")) > 2000, "PDF canvas is blank");
  const fig = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-pdf")));
  assert.deepEqual(fig.series.map((s) => s.name), ["k̃2 = 5", "k̃2 = 20", "k̃2 = 110", "k̃2 = 580", "k̃2 = ∞"]);
  const peaks = fig.series.map((s) => Math.max(...s.y.filter((v) => v !== null)));
  const expected = [6.86, 5.24, 3.71, 3.11, 2.97]; // theory.md §4, peak of Φ
  peaks.forEach((p, i) => assert.ok(Math.abs(p - expected[i]) < 0.03, `peak ${i}: ${p}`));
  const masses = await page.$$eval("#readout-pdf table tr td:nth-child(2)", (t) => t.map((e) => Number(e.textContent)));
  assert.equal(masses.length, 5);
  masses.forEach((m) => assert.ok(Math.abs(m - 1) < 1e-3, `mass ${m}`));
});

test("Fig. 2 preset: the paper's iteration, one PDF per Vmax", async () => {
  assert.match(await runAndWait('[data-preset="fig2"]'), /^Done: 4 requests/);
  assert.ok((await inked("plot-pdf")) > 2000, "PDF canvas is blank");
  const fig = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-pdf")));
  assert.deepEqual(fig.series.map((s) => s.name),
    ["0.1", "0.05", "0.025", "0.0025"].map((v) => `Vmax = ${v}, k̃2 = 5`));
  const json = await page.evaluate(() => JSON.parse(LJApp.panelJSON("pdf")));
  assert.deepEqual(json.requests.map((r) => r.body.vmax), [0.1, 0.05, 0.025, 0.0025]);
  assert.ok(json.requests.every((r) => r.body.method === "paper" && r.body.psd.C === 0.0795775));
  assert.ok(json.requests.every((r) => r.body.fixed_vmax === true));
  // the inset of the paper's Fig. 2 (theory.md §4): peaks ≈ 5.5, 6.1, 6.5, 6.7 near g̃ = 0.89,
  // rising as Vmax falls (values read off the figure: 6 %)
  const peaks = fig.series.map((s) => Math.max(...s.y.filter((v) => v !== null)));
  [5.5, 6.1, 6.5, 6.7].forEach((ref, i) => assert.ok(Math.abs(peaks[i] - ref) < 0.06 * ref, `peak ${peaks[i]} vs ${ref}`));
  for (let i = 1; i < 4; i++) assert.ok(peaks[i] > peaks[i - 1], String(peaks));
});

test("Fig. 5 preset: sweep on a log axis, Δγeff and σ̄max fall as m̃0 grows", async () => {
  assert.match(await runAndWait('[data-preset="fig5a"]'), /^Done/);
  assert.ok((await inked("plot-sweep")) > 1000, "sweep canvas is blank");
  const fig = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-sweep")));
  assert.equal(fig.xLog, true);
  for (const s of fig.series) {
    assert.equal(s.y.length, 13);
    for (let i = 1; i < s.y.length; i++) assert.ok(s.y[i] < s.y[i - 1], `${s.name} not falling at ${i}`);
  }
  // the flat surface (m0 -> 0) bounds both from above (theory.md §2)
  assert.ok(fig.series.every((s) => s.y.every((v) => v > 0 && v < 1)));
});

test("a 422 problem appears beside the field its pointer names", async () => {
  await page.click('[data-preset="fig4"]');
  await page.waitForFunction(() => document.getElementById("busy").hidden && /^Done/.test(document.getElementById("status-text").textContent));
  await page.fill("#k1", "0.3");
  await page.fill("#g-n", "many");
  // the request the form gives, and the server's answer to it (see the note at the top)
  const body = (await page.evaluate(() => LJApp.requests())).find((r) => r.panel === "traction").body;
  assert.equal(body.psd.k1, 0.3);
  assert.equal(body.g_ave.n, "many"); // not a number: the server, not the page, says so
  const res = await fetch(`${origin}/v1/traction`, { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
  assert.equal(res.status, 422);
  const problem = await res.json();
  assert.equal(problem.type, "/problems/validation");
  await page.evaluate((p) => LJApp.showProblem("traction", 422, p), problem);
  assert.match(await page.textContent("#readout-traction"), /422 Invalid request/);
  assert.match(await page.textContent('.err[data-for="k1"]'), /k0 = 0\.46978/);
  assert.match(await page.textContent('.err[data-for="g-n"]'), /number/);
  assert.equal(await page.getAttribute("#k1", "aria-invalid"), "true");
  assert.equal(await page.textContent('.err[data-for="exp"]'), "");
  // and the error goes away once the field is edited
  await page.fill("#k1", "1");
  assert.equal(await page.textContent('.err[data-for="k1"]'), "");
});

test("exports: CSV, JSON, PNG of the plot and copy as curl with the exact request", async () => {
  assert.match(await runAndWait('[data-preset="fig4"]'), /^Done/);
  const save = async (sel) => {
    const [dl] = await Promise.all([page.waitForEvent("download"), page.click(sel)]);
    return fs.readFileSync(await dl.path());
  };
  // the traction CSV is the server's own for the same request: units, the summary with its
  // errors, the request itself, one row per gap with its error
  const csv = (await save('[data-panel="traction"] [data-export="csv"]')).toString().trim().split("\n");
  assert.match(csv[0], /^# request: POST \/v1\/traction \{"psd":\{"kind":"power","D":2\.5/);
  assert.ok(csv.some((l) => /^# summary\.g_eq \[eps\] = 2\.602\d* ± \d/.test(l)), "g_eq with its unit and error");
  assert.ok(csv.some((l) => /^# summary\.dgamma_eff \[dgamma\] = 0\.201\d* ± /.test(l)), "Δγeff with its unit");
  const head = csv.findIndex((l) => !l.startsWith("#"));
  assert.equal(csv[head], "g_ave [eps],sigma [sigma0],sigma_err [sigma0]");
  assert.equal(csv.length - head - 1, 200, "one row per gap");
  // the buttons say which card they export
  assert.equal(await page.textContent('[data-panel="traction"] [data-export="csv"]'), "Traction CSV");
  const json = JSON.parse(await save('[data-panel="traction"] [data-export="json"]'));
  assert.equal(json.series.length, 3);
  assert.equal(json.requests[0].url, `${origin}/v1/traction`);
  const png = await save('[data-panel="traction"] [data-export="png"]');
  assert.deepEqual([...png.subarray(0, 8)], [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]);
  assert.ok(png.length > 5000);
  // at twice the chart's size (IHDR width), with the parameters printed under it
  const plotWidth = await page.evaluate(() => document.querySelector("#plot-traction canvas").clientWidth);
  assert.ok(png.readUInt32BE(16) >= 2 * plotWidth, `PNG ${png.readUInt32BE(16)} px for a ${plotWidth} px chart`);
  await page.click('[data-panel="traction"] [data-export="copy-as-curl"]');
  const curl = await page.inputValue("#curl-text");
  assert.match(curl, new RegExp(`^curl -s ${origin}/v1/traction `));
  await page.click("#curl-dialog button");
  // the command, run by a shell, answers what the page plotted
  const answer = JSON.parse(execFileSync("bash", ["-c", curl]).toString());
  assert.deepEqual(answer.sigma, json.answers[0].sigma);
  assert.deepEqual(answer.summary, json.answers[0].summary);
});

test("table PSD uploaded as CSV: traction drawn, table and tail in the PSD plot; bad rows refused", async () => {
  await page.click('[data-preset="fig4"]');
  await page.waitForFunction(() => document.getElementById("busy").hidden && /^Done/.test(document.getElementById("status-text").textContent));
  await page.check('input[name="kind"][value="table"]');
  // the power law of Fig. 4 sampled: P = C k^(2D-8) with the tail exponent 2D - 8 = -3
  const C = 0.0795775;
  const rows = [1, 2, 4, 8, 16].map((k) => `${k},${C * Math.pow(k, -3)}`);
  await page.setInputFiles("#table-file", { name: "psd.csv", mimeType: "text/csv", buffer: Buffer.from(`k,P\n${rows.join("\n")}\n`) });
  await page.waitForFunction(() => document.getElementById("table").value.startsWith("k,P"));
  await page.fill("#tail", "-3");
  assert.match(await runAndWait("#compute"), /^Done: 1 request/);
  assert.ok((await inked("plot-traction")) > 2000);
  const fig = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-psd")));
  assert.deepEqual(fig.series.map((s) => s.name), ["P̃S table", "tail ∝ k^-3"]);
  // the same spectrum as Fig. 4, so the same answer (log-log interpolation of a power law is exact)
  const geq = Number((await page.$$eval("#readout-traction table tr td:nth-child(2)", (t) => t.map((e) => e.textContent)))[0]);
  assert.ok(Math.abs(geq - 2.6028) < 2e-4, `g_eq ${geq}`);
  await page.fill("#table", "k,P\n1,0.08\n2 oops\n");
  await runAndWait("#compute");
  assert.match(await page.textContent('.err[data-for="table"]'), /line 3/);
  await page.check('input[name="kind"][value="power"]');
});

test("issue 29: a table with P_err: the traction's uncertainty band and Δγeff ± measurement ± solver", async () => {
  await page.click('[data-preset="fig4"]');
  await page.waitForFunction(() => document.getElementById("busy").hidden && /^Done/.test(document.getElementById("status-text").textContent));
  await page.check('input[name="kind"][value="table"]');
  const C = 0.0795775;
  const upload = async (withErr) => {
    const rows = [1, 2, 4, 8, 16].map((k) => `${k},${C * Math.pow(k, -3)}${withErr ? `,${0.1 * C * Math.pow(k, -3)}` : ""}`);
    await page.setInputFiles("#table-file", { name: "psd.csv", mimeType: "text/csv", buffer: Buffer.from(`k,P${withErr ? ",P_err" : ""}\n${rows.join("\n")}\n`) });
    await page.waitForFunction((h) => document.getElementById("table").value.startsWith(h), withErr ? "k,P,P_err" : "k,P\n");
    await page.fill("#tail", "-3");
    assert.match(await runAndWait("#compute"), /^Done: 1 request/);
  };
  await upload(true);
  assert.match(await page.textContent("#readout-traction caption"),
    /^Δγeff\/Δγ = 0\.\d+ ± 0\.\d+ \(measurement\) ± \d\.\de-\d+ \(solver\)$/);
  const fig = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-traction")));
  assert.equal(fig.bands.length, 1, "one uncertainty band");
  const hi = fig.series[fig.bands[0].hi].y, lo = fig.series[fig.bands[0].lo].y, mid = fig.series[0].y;
  assert.ok(hi.every((v, i) => v === null || (v > mid[i] && lo[i] < mid[i])), "the band brackets the curve");
  assert.ok(hi.some((v) => v !== null), "the band has points");
  assert.match(await page.textContent("#readout-traction"), /orange band: ± the measurement's uncertainty/);
  // the same table without P_err: no band, no line
  await upload(false);
  assert.equal(await page.$("#readout-traction caption"), null);
  assert.equal((await page.evaluate(() => LJPlots.figure(document.getElementById("plot-traction")))).bands.length, 0);
  await page.check('input[name="kind"][value="power"]');
});

test("material and sphere radius: SI values and the contact panel", async () => {
  await page.click('[data-preset="fig4"]');
  await page.waitForFunction(() => document.getElementById("busy").hidden && /^Done/.test(document.getElementById("status-text").textContent));
  await page.check("#use-material");
  await page.fill("#R", "1e-6");
  assert.match(await runAndWait("#compute"), /^Done: 2 requests/);
  const contact = await page.textContent("#readout-contact");
  assert.match(contact, /JKR with Δγeff/);
  assert.match(contact, /regime/);
  assert.match(await page.textContent("#readout-traction"), /\d ± [^ ]+ J\/m²/); // SI values with their errors
  // issue 30: with a material the plots are in SI, a switch goes back to the paper's units;
  // the pull-off table and CSV carry units, μ, λ and the regime
  let tf = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-traction")));
  assert.deepEqual([tf.xLabel, tf.yLabel], ["gave (m)", "σ̄ (Pa)"]);
  assert.deepEqual(await page.$$eval("#readout-contact table tr:first-child th", (t) => t.map((e) => e.textContent)), ["quantity", "value", "unit", "± err"]);
  assert.match(await page.textContent("#readout-contact"), /Maugis λ[\d.e+-]+1/);
  const [dl] = await Promise.all([page.waitForEvent("download"), page.click('[data-panel="contact"] [data-export="csv"]')]);
  const pc = fs.readFileSync(await dl.path(), "utf8");
  assert.match(pc, /^quantity,value,unit,error$/m);
  assert.match(pc, /^pull_off_N\.jkr,[\d.e+-]+,N,[\d.e+-]+$/m);
  assert.match(pc, /^maugis_lambda,/m);
  assert.match(pc, /^regime,\w/m);
  // SI mode relabels k1 with its minimum from the material (χ = 3ε²E*/(16Δγ) = 3.375e-10 m)
  await page.selectOption("#units", "SI");
  assert.match(await page.textContent("#k1-label"), /^k1 \(lower cut-off, 1\/m, > k0\/χ = 1\.392e\+9 1\/m\)$/);
  assert.match(await page.textContent('#vary option[value="m0"]'), /m0 \(m²\)/);
  await page.selectOption("#units", "");
  assert.match(await page.textContent("#k1-label"), /^k̃1 /);
  await page.uncheck("#si-plots");
  assert.match(await runAndWait("#compute"), /^Done: 2 requests/);
  tf = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-traction")));
  assert.deepEqual([tf.xLabel, tf.yLabel], ["g̃ave", "σ̄/σ0"]);
  await page.check("#si-plots");
  await page.evaluate(() => window.scrollTo(0, 0));
  await page.screenshot({ path: path.join(BUILD, "web-screenshot-contact.png"), fullPage: true });
});

test("simulation jobs: a form with a progress bar when the server offers them, else none", async () => {
  const api = await (await fetch(`${origin}/openapi.json`)).json();
  const op = (api.paths || {})["/v1/simulations"];
  const offered = !!(op && op.post && !/planned/i.test(op.post.summary || ""));
  assert.equal(await page.isVisible("#jobs-card"), offered);
  if (!offered) return; // the server has no jobs: the page must not offer the form (checked above)
  await page.click('[data-preset="fig6"]');
  await page.waitForFunction(() => document.getElementById("busy").hidden && /^Done/.test(document.getElementById("status-text").textContent));
  await page.fill("#sim-n", "32");
  await page.fill("#sim-real", "2");
  await page.fill("#sim-g", "1.5, 2, 3");
  await page.click("#sim-start");
  await page.waitForFunction(() => /done in|failed|cancelled/.test(document.getElementById("sim-state").textContent), null, { timeout: 60000 });
  assert.match(await page.textContent("#sim-state"), /done in/);
  assert.equal(await page.evaluate(() => document.getElementById("sim-progress").value), 1);
  assert.ok((await inked("plot-jobs")) > 500, "jobs canvas is blank");
  const fig = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-jobs")));
  assert.deepEqual(fig.series.map((x) => x.name), ["σ̄/σ0 numerical model", "σ̄/σ0 statistical theory"]);
  assert.deepEqual(fig.series[0].x, [1.5, 2, 3]);
  // the hybrid (k_split) and the full model beside it: theory, hybrid and full model in one plot
  assert.equal(await page.isVisible("#sim-full-field"), false);
  await page.fill("#sim-ksplit", "3");
  assert.equal(await page.isVisible("#sim-full-field"), true);
  await page.fill("#sim-n", "16");
  await page.check("#sim-full");
  await page.fill("#sim-nfull", "32");
  await page.click("#sim-start");
  await page.waitForFunction(() => /done in .* \+ |failed|cancelled|refused/.test(document.getElementById("sim-state").textContent), null, { timeout: 60000 });
  assert.match(await page.textContent("#sim-state"), /done in/);
  const hyb = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-jobs")));
  assert.deepEqual(hyb.series.map((x) => x.name), ["σ̄/σ0 hybrid (k̃split = 3)", "σ̄/σ0 numerical model", "σ̄/σ0 statistical theory"]);
  assert.match(await page.textContent("#readout-fine"), /fine band .* m̃0 = 0\.0308\d*; .* g̃eq = 1\.04\d* ±/);
  assert.match(await page.textContent("#readout-compare"), /largest \|hybrid − full\| = 0\.\d+ σ0 at g̃ave = /);
  const jobsJSON = JSON.parse(await page.evaluate(() => LJApp.panelJSON("jobs")));
  assert.deepEqual(jobsJSON.requests.map((r) => r.url.replace(/.*\/v1\//, "")), ["simulations", "simulations", "traction"]);
  assert.equal(jobsJSON.requests[0].body.k_split, 3);
  assert.equal(jobsJSON.requests[1].body.k_split, undefined);
  assert.equal(jobsJSON.requests[1].body.n, 32);
  await page.fill("#sim-ksplit", "");
  // a bad grid answers 422 at once, beside the field (the server's answer, see the note at the top)
  await page.fill("#sim-n", "33");
  const body = await page.evaluate(() => LJJobs.request());
  assert.equal(body.n, 33);
  const res = await fetch(`${origin}/v1/simulations`, { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
  assert.equal(res.status, 422);
  const problem = await res.json();
  await page.evaluate((p) => LJJobs.refused(422, p), problem);
  assert.equal(await page.evaluate(() => document.getElementById("sim-state").dataset.status), "refused");
  assert.match(await page.textContent('.err[data-for="sim-n"]'), /even/);
  // issue 30: the header says so (not "Ready.") and the view and focus are on the field
  assert.match(await page.textContent("#status-text"), /^The simulation was refused \(422\): see the highlighted field\.$/);
  assert.equal(await page.evaluate(() => document.activeElement.id), "sim-n");
  assert.match(await page.textContent("#sim-state"), /^422 Invalid request: /);
});

test("measured topography: upload, PSD and fit on log axes, k1 and k2 picked on the plot, adhesion", async () => {
  // a 128² synthetic map (bench/topo gen: D = 2.3, dx = 10 nm, h_rms 5 nm) as a text file
  const file = path.join(userDir, "map.txt");
  execFileSync(path.join(BUILD, "bench/topo"), ["gen", file, "128"]);
  await page.check("#use-material");
  await page.selectOption("#modulus-kind", "E_star");
  await page.fill("#E_star", "1e11"); // χ = 34 nm: k0/χ = 1.4e7 1/m, inside the map's band
  await page.setInputFiles("#topo-file", file);
  await page.fill("#topo-dx", "1e-8");
  await page.click("#topo-compute");
  await page.waitForFunction(() => /^PSD of|refused/.test(document.getElementById("status-text").textContent));
  assert.match(await page.textContent("#status-text"), /^PSD of map\.txt: \d+ bins/);
  assert.ok(await page.isVisible("#card-topo"));
  assert.ok((await inked("plot-topo")) > 500, "topography PSD canvas is blank");
  const fig = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-topo")));
  assert.equal(fig.xLog && fig.yLog, true);
  assert.equal(fig.series[0].name, "P (bins, m⁴)");
  assert.match(fig.series[1].name, /^fit: D = /);
  assert.ok(fig.marks.some((m) => m.label === "k0/χ") && fig.marks.some((m) => m.label === "k1"));
  const rows = await page.$$eval("#readout-topo table tr", (r) => r.map((x) => [...x.children].map((c) => c.textContent)));
  const byName = Object.fromEntries(rows.map((r) => [r[0], r.slice(1)]));
  const D = Number(byName["D (H = 3 − D)"][0]);
  assert.ok(Math.abs(D - 2.3) < 0.1, `D ${D}`);
  assert.match(byName["D (H = 3 − D)"][1], /^± \d\.\de-\d+$/);
  assert.match(byName.h_rms[0], /e-9 m$/);
  assert.match(await page.textContent("#readout-topo"), /theory's domain k > k0\/χ/);
  const k1 = Number(await page.inputValue("#topo-k1"));
  assert.ok(k1 >= 1.1 * 0.46978 / 3.375e-8 * 0.999, `k1 ${k1}`);
  // a click on the plot sets k2 where the cursor is
  await page.selectOption("#topo-pick", "k2");
  const box = await page.locator("#plot-topo .u-over").boundingBox();
  await page.mouse.click(box.x + box.width * 0.8, box.y + box.height * 0.5);
  const k2 = Number(await page.inputValue("#topo-k2"));
  assert.ok(k2 > k1 && Number.isFinite(k2), `k2 ${k2} after the click`);
  assert.ok((await page.evaluate(() => LJPlots.figure(document.getElementById("plot-topo")))).marks.some((m) => m.label === "k2"));
  await page.click("#topo-adhesion");
  await page.waitForFunction(() => /^Adhesion of the measured|refused/.test(document.getElementById("status-text").textContent), null, { timeout: 60000 });
  assert.match(await page.textContent("#status-text"), /Δγeff\/Δγ = /);
  const ad = await page.textContent("#readout-topo-adhesion");
  assert.match(ad, /Δγeff\/Δγ/);
  assert.match(ad, new RegExp(`to k2 = `));
  /* the measured table's model: read as a table (its variance-weighted D), said on or off the map */
  assert.match(await page.textContent("#readout-topo-adhesion .validity-line"), /model: /);
  const json = await page.evaluate(() => JSON.parse(LJApp.panelJSON("topo")));
  const adReq = json.requests.find((r) => r.label === "adhesion").body;
  assert.equal(adReq.units, "SI");
  assert.equal(adReq.psd.k[0], k1);
  assert.equal(adReq.psd.k[adReq.psd.k.length - 1], k2);
  await page.evaluate(() => document.getElementById("card-topo").scrollIntoView());
  await page.screenshot({ path: path.join(BUILD, "web-screenshot-topo.png"), fullPage: true });
  // a bad matrix: the line and column beside the file field (the server's answer to the upload
  // the page would send, see the note at the top)
  const q = await page.evaluate(() => LJTopo.query());
  const res = await fetch(`${origin}/v1/psd?${q}`, { method: "POST", headers: { "Content-Type": "text/plain" }, body: "1 2 3\n4 x 6\n" });
  assert.equal(res.status, 422);
  await page.evaluate((p) => LJTopo.refused(422, p), await res.json());
  assert.match(await page.textContent("#status-text"), /refused/);
  assert.match(await page.textContent('.err[data-for="topo-file"]'), /line 2, column 3/);
  // issue 30: nothing of the good map before stays under the 422 (plot, k1, the adhesion)
  assert.equal(await page.evaluate(() => LJPlots.figure(document.getElementById("plot-topo"))), null);
  assert.equal(await page.inputValue("#topo-k1"), "");
  assert.equal(await page.textContent("#readout-topo-adhesion"), "");
  await page.fill("#E_star", "1e9");
});

test("several measured maps: each one's PSD, their combination with its error band, the CSV", async () => {
  // one surface (bench/topo gen's law, D = 2.3) measured at 10 nm and 2 nm pixels, 128² each
  const coarse = path.join(userDir, "coarse-10nm.txt");
  const fine = path.join(userDir, "fine-2nm.txt");
  execFileSync(path.join(BUILD, "bench/topo"), ["gen", coarse, "128"]);
  execFileSync(path.join(BUILD, "bench/topo"), ["gen", fine, "128", "2e-9"]);
  await page.uncheck("#use-material");
  await page.setInputFiles("#topo-file", [coarse, fine]);
  assert.ok(await page.isVisible("#topo-files"));
  await page.fill("#topo-dx-0", "1e-8");
  await page.fill("#topo-dx-1", "2e-9");
  await page.evaluate(() => (document.getElementById("status-text").textContent = "")); // the last test ended refused
  await page.click("#topo-compute");
  await page.waitForFunction(() => /^Combined PSD|refused|failed/.test(document.getElementById("status-text").textContent));
  assert.match(await page.textContent("#status-text"), /^Combined PSD of 2 measurements: \d+ points/);
  assert.ok((await inked("plot-topo")) > 500, "combined PSD canvas is blank");
  const fig = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-topo")));
  const names = fig.series.map((x) => x.name);
  assert.deepEqual(names.slice(0, 5), ["coarse-10nm.txt (bins, m⁴)", "fine-2nm.txt (bins, m⁴)", "combined P (m⁴)", "combined P + P_err", "combined P − P_err"]);
  assert.match(names[5], /^fit: D = /);
  const rows = await page.$$eval("#readout-topo table tr", (r) => r.map((x) => [...x.children].map((c) => c.textContent)));
  const D = Number(Object.fromEntries(rows.map((r) => [r[0], r.slice(1)]))["D (H = 3 − D)"][0]);
  assert.ok(Math.abs(D - 2.3) < 0.05, `combined D ${D}`);
  const ro = await page.textContent("#readout-topo");
  assert.match(ro, /coarse-10nm\.txt: k = .* 1\/m, \d+ points of the combination/);
  assert.match(ro, /overlap: χ² = /);
  const json = await page.evaluate(() => JSON.parse(LJApp.panelJSON("topo")));
  assert.deepEqual(json.requests.map((r) => r.label), ["psd coarse-10nm.txt", "psd fine-2nm.txt", "psd/combine"]);
  assert.equal(json.requests[2].body.psds.length, 2);
  assert.ok(json.requests[2].body.psds.every((x) => x.P_err.length === x.k.length));
  // each /v1/psd answer's psd object as it is (no table of the page's own)
  assert.deepEqual(json.requests[2].body.psds, [json.answers[0].psd, json.answers[1].psd]);
  assert.equal(json.requests[2].body.material, undefined);
  // the combination's CSV, with units
  const [dl] = await Promise.all([page.waitForEvent("download"), page.click("#topo-combined-csv")]);
  const csv = fs.readFileSync(await dl.path(), "utf8").split("\n");
  assert.equal(dl.suggestedFilename(), "ljgap-topo-combined.csv");
  assert.ok(csv.includes("k [1/m],P [m^4],P_err [m^4],inputs"));
  const answer = json.answers[2];
  assert.equal(csv.filter((l) => /^\d/.test(l)).length, answer.k.length);
  // with a material: the combine takes it (not /v1/psd), answers the domain, and the adhesion
  // sends the combined psd object from the domain's k1
  await page.check("#use-material");
  await page.fill("#E_star", "1e11");
  await page.evaluate(() => (document.getElementById("status-text").textContent = ""));
  await page.click("#topo-compute");
  await page.waitForFunction(() => /^Combined PSD|refused|failed/.test(document.getElementById("status-text").textContent));
  const jm = await page.evaluate(() => JSON.parse(LJApp.panelJSON("topo")));
  assert.deepEqual(jm.requests.map((r) => r.label), ["psd coarse-10nm.txt", "psd fine-2nm.txt", "psd/combine"]);
  assert.equal(jm.requests[2].body.material.E_star, 1e11);
  const cm = jm.answers[2];
  assert.ok(cm.domain && cm.si, "the combine's domain and si");
  assert.equal(cm.psd.k[0], cm.domain.k1);
  assert.match(await page.textContent("#readout-topo"), /theory's domain k > k0\/χ = .* the psd object starts at k1 = /);
  assert.equal(Number(await page.inputValue("#topo-k1")), Number(cm.domain.k1.toPrecision(6)));
  await page.fill("#topo-k1", String(cm.psd.k[0]));
  await page.click("#topo-adhesion");
  await page.waitForFunction(() => /^Adhesion of the measured|refused/.test(document.getElementById("status-text").textContent), null, { timeout: 60000 });
  assert.match(await page.textContent("#status-text"), /Δγeff\/Δγ = /);
  const ja = await page.evaluate(() => JSON.parse(LJApp.panelJSON("topo")));
  const adh = ja.requests[ja.requests.length - 1];
  assert.equal(adh.label, "adhesion");
  assert.deepEqual(adh.body.psd, cm.psd, "the adhesion takes the combined psd object");
  // k1 and k2 changed: that psd object cut to them, P_err kept
  await page.fill("#topo-k1", String(cm.psd.k[2]));
  await page.fill("#topo-k2", String(cm.psd.k[cm.psd.k.length - 2]));
  await page.click("#topo-adhesion");
  await page.waitForFunction(() => /^Adhesion of the measured|refused/.test(document.getElementById("status-text").textContent), null, { timeout: 60000 });
  const jc = await page.evaluate(() => JSON.parse(LJApp.panelJSON("topo")));
  const cutPsd = jc.requests[jc.requests.length - 1].body.psd;
  assert.deepEqual(cutPsd.k, cm.psd.k.slice(2, -1));
  assert.deepEqual(cutPsd.P_err, cm.psd.P_err.slice(2, -1));
  assert.equal(cutPsd.tail, undefined);
  await page.fill("#topo-k1", String(cm.psd.k[0]));
  await page.fill("#topo-k2", "");
  // issue 30: "Use this spectrum" after a combine: the combined psd object is the calculation's
  await page.click("#topo-use");
  await page.waitForFunction(() => document.getElementById("busy").hidden && /^Done|problem|failed/.test(document.getElementById("status-text").textContent), null, { timeout: 60000 });
  assert.match(await page.textContent("#status-text"), /^Done: 2 requests/);
  const used = (await page.evaluate(() => JSON.parse(LJApp.panelJSON("traction")))).requests[0].body;
  assert.deepEqual(used.psd, cm.psd, "the combined psd object as it is");
  assert.equal(used.units, "SI");
  assert.ok((await inked("plot-traction")) > 2000, "traction canvas is blank");
  await page.check('input[name="kind"][value="power"]');
  await page.selectOption("#units", "");
  await page.evaluate(() => document.getElementById("card-topo").scrollIntoView());
  await page.screenshot({ path: path.join(BUILD, "web-screenshot-combine.png"), fullPage: false });
  await page.setViewportSize({ width: 390, height: 844 });
  await page.evaluate(() => document.getElementById("card-topo").scrollIntoView());
  await page.screenshot({ path: path.join(BUILD, "web-screenshot-combine-phone.png"), fullPage: false });
  await page.setViewportSize({ width: 1280, height: 900 });
  await page.evaluate(() => document.getElementById("card-topo").scrollIntoView());
  await page.screenshot({ path: path.join(BUILD, "web-screenshot-combine-1280.png"), fullPage: false });
  await page.fill("#E_star", "1e9");
  await page.uncheck("#use-material");
});

test("issue 30: a height map through \"Use this spectrum\" to traction, PDF and pull-off in SI", async () => {
  const file = path.join(userDir, "use-map.txt");
  execFileSync(path.join(BUILD, "bench/topo"), ["gen", file, "128"]);
  await page.setViewportSize({ width: 1280, height: 900 });
  await page.check("#use-material");
  await page.selectOption("#modulus-kind", "E_star");
  await page.fill("#E_star", "1e11");
  await page.fill("#R", "1e-5");
  await page.setInputFiles("#topo-file", file);
  await page.fill("#topo-dx", "1e-8");
  await page.click("#topo-compute");
  await page.waitForFunction(() => /^PSD of|refused/.test(document.getElementById("status-text").textContent));
  // issue 30: the card says what it was computed for, and when its inputs change since
  const forText = () => page.textContent("#topo-for");
  assert.match(await forText(), /^computed for: use-map\.txt; dx = 1e-8 m; dy = dx; not periodic; material E_star = 100000000000, dgamma = 0\.05, epsilon = 3e-10; (plane|mean|\w+) removed, Hann window$/);
  await page.fill("#topo-dx", "2e-8");
  assert.match(await forText(), /dx = 1e-8 m; .* — the inputs above have changed since: Compute PSD again$/);
  assert.equal(await page.getAttribute("#topo-for", "class"), "meta computed-for stale");
  await page.fill("#topo-dx", "1e-8");
  assert.doesNotMatch(await forText(), /changed since/);
  await page.check("#topo-periodic");
  assert.match(await forText(), /changed since/);
  await page.uncheck("#topo-periodic");
  assert.doesNotMatch(await forText(), /changed since/);
  // the fit band and the reliable band on the PSD plot
  const tf = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-topo")));
  assert.ok(tf.marks.filter((m) => m.label === "fit band").length === 2, "fit band marked");
  assert.ok(tf.marks.some((m) => m.label === "reliable from"), "reliable band marked");
  assert.equal(await page.getAttribute("#topo-use", "class"), "primary");
  assert.match(await page.textContent("#topo-use"), /^Use this spectrum$/);
  await page.click("#topo-use");
  await page.waitForFunction(() => document.getElementById("busy").hidden && /^Done|problem|failed/.test(document.getElementById("status-text").textContent), null, { timeout: 60000 });
  assert.match(await page.textContent("#status-text"), /^Done: 3 requests/);
  assert.ok((await inked("plot-traction")) > 2000, "traction canvas is blank");
  assert.ok((await inked("plot-pdf")) > 1000, "PDF canvas is blank");
  assert.ok(await page.isVisible("#card-contact"), "the pull-off card");
  assert.match(await page.textContent("#readout-contact"), /pull-off, JKR with Δγeff.*N/);
  assert.match(await page.textContent("#readout-traction"), /J\/m²/); // Δγeff in SI
  assert.equal((await page.evaluate(() => LJPlots.figure(document.getElementById("plot-traction")))).xLabel, "gave (m)");
  assert.match(await page.textContent("#readout-traction"), /computed for: table PSD of \d+ points.*1\/m.*SI; material E_star = 100000000000/);
  const j = await page.evaluate(() => JSON.parse(LJApp.panelJSON("traction")));
  const body = j.requests[0].body;
  assert.equal(body.units, "SI");
  assert.equal(body.material.E_star, 1e11);
  assert.equal(body.psd.kind, "table");
  assert.equal(body.psd.P_err.length, body.psd.k.length, "the psd object's errors go along");
  assert.equal(body.psd.P_corr.length, body.psd.k.length - 1, "and the knots' correlations (issue 29)");
  assert.match(await page.textContent("#readout-traction caption"), /\(measurement\) ± .* \(solver\)$/);
  const topo = await page.evaluate(() => JSON.parse(LJApp.panelJSON("topo")));
  assert.equal(body.psd.k[0], Number(await page.inputValue("#topo-k1")));
  assert.ok(body.psd.k.length > 3 && topo.answers[0].psd.k.includes(body.psd.k[1]));
  // the g̃ range is placed about g̃eq, and the PDF is asked at g̃eq
  const geq = j.answers[0].summary.g_eq;
  assert.ok(body.g_ave.min < geq && body.g_ave.max > geq, `g range ${JSON.stringify(body.g_ave)} about ${geq}`);
  // the view is on the results
  const top = await page.evaluate(() => document.getElementById("card-traction").getBoundingClientRect().top);
  assert.ok(top >= 0 && top < 900, `traction card at ${top}`);
  // the card's own CSV export reads back into the table input
  const [dl] = await Promise.all([page.waitForEvent("download"), page.click('[data-panel="topo"] [data-export="csv"]')]);
  const csv = fs.readFileSync(await dl.path(), "utf8");
  assert.match(csv, /^k \[1\/m\],P \[m\^4\],P_err \[m\^4\]$/m);
  await page.fill("#table", csv);
  const back = (await page.evaluate(() => LJApp.requests())).find((r) => r.panel === "traction").body.psd;
  assert.deepEqual(back.k, topo.answers[0].psd.k);
  await page.screenshot({ path: path.join(BUILD, "web-screenshot-use-spectrum.png"), fullPage: false });
  await page.fill("#R", "");
  await page.fill("#E_star", "1e9");
  await page.uncheck("#use-material");
});

test("issue 30: \"Use this spectrum\" of a map whose spectrum has no tail asks the PDF at the table's end", async () => {
  // a smooth random map (a few long waves and a little noise): its fit is no power law with
  // 2 < D < 3, so the server's psd object has no tail and the PDF cannot be asked at k̃2 = ∞
  let seed = 7;
  const rnd = () => ((seed = (seed * 16807) % 2147483647) / 2147483647);
  const waves = Array.from({ length: 12 }, () => [2 * Math.PI * (1 + 6 * rnd()) / 64, 2 * Math.PI * rnd(), 2e-9 * (rnd() - 0.5), 2 * Math.PI * rnd()]);
  const rows = [];
  for (let j = 0; j < 64; j++) {
    const row = [];
    for (let i = 0; i < 64; i++) row.push((waves.reduce((h, [k, th, a, ph]) => h + a * Math.sin(k * (Math.cos(th) * i + Math.sin(th) * j) + ph), 0) + 1e-11 * (rnd() - 0.5)).toExponential(4));
    rows.push(row.join(" "));
  }
  await page.check("#use-material");
  await page.selectOption("#modulus-kind", "E_star");
  await page.fill("#E_star", "1e11");
  await page.setInputFiles("#topo-file", { name: "smooth.txt", mimeType: "text/plain", buffer: Buffer.from(rows.join("\n") + "\n") });
  await page.fill("#topo-dx", "1e-8");
  await page.click("#topo-compute");
  await page.waitForFunction(() => /^PSD of|refused/.test(document.getElementById("status-text").textContent));
  const topo = await page.evaluate(() => JSON.parse(LJApp.panelJSON("topo")));
  assert.equal(topo.answers[0].psd.tail, undefined, "a spectrum without a tail");
  await page.click("#topo-use");
  await page.waitForFunction(() => document.getElementById("busy").hidden && /^Done|problem|failed/.test(document.getElementById("status-text").textContent), null, { timeout: 60000 });
  assert.match(await page.textContent("#status-text"), /^Done: 2 requests/);
  const k2 = (await page.evaluate(() => JSON.parse(LJApp.panelJSON("pdf")))).requests[0].body.k2;
  const q = topo.answers[0].psd;
  // k̃2 = χ k_end, χ = 3ε²E*/(16Δγ) = 3.375e-8 m (6 digits)
  assert.ok(Math.abs(k2[0] / (q.k[q.k.length - 1] * 3.375e-8) - 1) < 1e-5, `k2 ${k2}`);
  assert.ok((await inked("plot-pdf")) > 500, "PDF canvas is blank");
  await page.check('input[name="kind"][value="power"]');
  await page.selectOption("#units", "");
  await page.fill("#E_star", "1e9");
  await page.uncheck("#use-material");
});

test("issue 30: a binary file is one line, not a list of problems; nothing stale stays", async () => {
  const png = Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 13, 73, 72, 68, 82]);
  const before = requests.length;
  await page.setInputFiles("#topo-file", { name: "image.png", mimeType: "image/png", buffer: png });
  await page.click("#topo-compute");
  await page.waitForFunction(() => /not a height map/.test(document.getElementById("status-text").textContent));
  assert.equal(await page.textContent('.err[data-for="topo-file"]'), "not a height map: image.png is a PNG image; export the heights as text (one row a line) or send the instrument's own file");
  assert.equal(requests.slice(before).filter((u) => u.includes("/v1/")).length, 0, "nothing sent");
  // the previous map's plot and k1 are gone, its exports off
  assert.equal(await page.evaluate(() => LJPlots.figure(document.getElementById("plot-topo"))), null);
  assert.equal(await page.inputValue("#topo-k1"), "");
  assert.equal(await page.isDisabled('[data-panel="topo"] [data-export="csv"]'), true);
  // Fig. 6 (traction and sweep), then Fig. 4 (traction only): no sweep of Fig. 6 stays
  await page.setInputFiles("#topo-file", []);
  assert.match(await runAndWait('[data-preset="fig6"]'), /^Done/);
  assert.ok((await inked("plot-sweep")) > 500);
  assert.match(await runAndWait('[data-preset="fig4"]'), /^Done/);
  assert.equal(await page.textContent("#readout-sweep"), "No result yet.");
  assert.equal(await page.evaluate(() => LJPlots.figure(document.getElementById("plot-sweep"))), null);
  assert.equal(await page.isDisabled('[data-panel="sweep"] [data-export="csv"]'), true);
  assert.match(await page.textContent("#readout-traction"), /computed for: D = 2\.5; C = 0\.0795775; k1 = 1; k2 = ∞; dimensionless/);
});

// A NanoScope file of two 64 × 48 channels, Height and ZSensor (16-bit, the Z scale's value over
// 65536 times the sensitivity in nm/V), written from its documentation: the text header, then
// the images as little-endian int16.
function nanoscopeFile() {
  const nx = 64, ny = 48, hdr = 4096, n = nx * ny * 2;
  const lines = ["\\*File list", "\\Version: 0x05120005", `\\Data length: ${hdr}`, "\\Date: 09:30:00 AM Mon Jun 03 2019",
    "\\*Equipment list", "\\Microscope: Dimension Icon", "\\*Scanner list", "\\@Sens. Zsens: V 20 nm/V", "\\@Sens. ZsensSens: V 100 nm/V"];
  ["Height", "ZSensor"].forEach((t, c) => lines.push("\\*Ciao image list", `\\Data offset: ${hdr + c * n}`, `\\Data length: ${n}`, "\\Bytes/pixel: 2",
    `\\Samps/line: ${nx}`, `\\Number of lines: ${ny}`, "\\Scan Size: 640 480 nm", `\\@2:Image Data: S [${t}] "${t}"`,
    `\\@2:Z scale: V [Sens. ${c ? "ZsensSens" : "Zsens"}] (0.0001 V/LSB) 6.5536 V`));
  lines.push("\\*File list end");
  const head = Buffer.alloc(hdr);
  head.write(lines.join("\r\n") + "\r\n", "latin1");
  const data = Buffer.alloc(2 * n);
  for (let c = 0; c < 2; c++)
    for (let j = 0; j < ny; j++)
      for (let i = 0; i < nx; i++)
        data.writeInt16LE(Math.round(8000 * Math.sin(0.3 * i + 0.2 * j + c) + 3000 * Math.cos(0.05 * i * j) + ((i * 7919 + j * 104729) % 997) - 498), c * n + 2 * (j * nx + i));
  return Buffer.concat([head, data]);
}

test("issue 28: an instrument file chosen or dropped: its PSD, what the file said, its channels (desktop and 390 px)", async () => {
  await page.uncheck("#use-material");
  const spm = nanoscopeFile();
  await page.setInputFiles("#topo-file", { name: "scan.spm", mimeType: "application/octet-stream", buffer: spm });
  await page.fill("#topo-dx", "5e-9"); // the file's own spacing (10 nm) wins: dx is not sent
  await page.click("#topo-compute");
  await page.waitForFunction(() => /^PSD of|refused/.test(document.getElementById("status-text").textContent));
  assert.match(await page.textContent("#status-text"), /^PSD of scan\.spm: \d+ bins/);
  const ro = await page.textContent("#readout-topo");
  assert.match(ro, /file: nanoscope, channel "Height" of 2; 64 × 48 points, 6\.400e-7 × 4\.800e-7 m; heights in nm; instrument Bruker Dimension Icon; acquired 2019-06-03T09:30:00; no point missing/);
  const json = await page.evaluate(() => JSON.parse(LJApp.panelJSON("topo")));
  const up = JSON.parse(json.requests[json.requests.length - 1].text || JSON.stringify(json.requests[json.requests.length - 1].body));
  assert.equal(up.content_type, "application/octet-stream");
  assert.ok(!/(^|&)dx=/.test(up.query), `the file's query ${up.query} has no dx`);
  assert.equal(json.answers[json.answers.length - 1].grid.dx, 1e-8);
  // the channels of the answer fill the selector; another one sends the file again
  assert.ok(await page.isVisible("#topo-channel"));
  assert.deepEqual(await page.$$eval("#topo-channel option", (o) => o.map((x) => x.textContent)), ["0: Height", "1: ZSensor"]);
  await page.selectOption("#topo-channel", "1");
  await page.waitForFunction(() => /channel "ZSensor"/.test(document.getElementById("readout-topo").textContent));
  assert.ok((await inked("plot-topo")) > 500, "the PSD of the second channel is drawn");
  // at 390 px, a file dropped on the card: the same, and the page does not scroll sideways
  await page.setViewportSize({ width: 390, height: 844 });
  await page.setInputFiles("#topo-file", []);
  const dt = await page.evaluateHandle((bytes) => {
    const d = new DataTransfer();
    d.items.add(new File([new Uint8Array(bytes)], "dropped.spm", { type: "application/octet-stream" }));
    return d;
  }, [...spm]);
  await page.dispatchEvent("#topo-card", "drop", { dataTransfer: dt });
  assert.equal(await page.evaluate(() => document.getElementById("topo-file").files[0].name), "dropped.spm");
  await page.click("#topo-compute");
  await page.waitForFunction(() => /^PSD of dropped/.test(document.getElementById("status-text").textContent));
  assert.match(await page.textContent("#readout-topo"), /file: nanoscope, channel "Height"/);
  const w = await page.evaluate(() => [document.documentElement.scrollWidth, document.body.scrollWidth]);
  assert.ok(w[0] <= 390 && w[1] <= 390, `page ${w[0]} px wide at 390 with the file's readout`);
  await page.setViewportSize({ width: 1400, height: 1000 });
  // bytes of no format read here: the server's 415 in the card, listing the formats
  await expect4xx(async () => {
    await page.setInputFiles("#topo-file", { name: "mystery.bin", mimeType: "application/octet-stream", buffer: Buffer.from([0, 1, 2, 3, 4, 5, 6, 7]) });
    await page.click("#topo-compute");
    await page.waitForFunction(() => /refused/.test(document.getElementById("status-text").textContent));
  });
  assert.match(await page.textContent("#readout-topo"), /415 .*nanoscope/);
  await page.setInputFiles("#topo-file", []);
});

test("issue 30: a bad field puts the view and the focus on it", async () => {
  await runAndWait('[data-preset="fig4"]');
  await page.evaluate(() => window.scrollTo(0, document.body.scrollHeight));
  await page.fill("#k1", "0.3");
  const status = await expect4xx(() => runAndWait("#compute-top"));
  assert.match(status, /^1 of 1 requests answered with a problem: see the highlighted field\.$/);
  assert.equal(await page.evaluate(() => document.activeElement.id), "k1");
  const r = await page.evaluate(() => { const b = document.getElementById("k1").getBoundingClientRect(); return [b.top, b.bottom, innerHeight]; });
  assert.ok(r[0] > 0 && r[1] < r[2], `k1 at ${r[0]}..${r[1]} of ${r[2]}`);
  assert.match(await page.textContent('.err[data-for="k1"]'), /k0 = 0\.46978/);
  assert.match(await page.textContent("#readout-traction"), /^422 /);
  assert.equal(await page.isDisabled('[data-panel="traction"] [data-export="csv"]'), true, "no result: no CSV");
  assert.equal(await page.isDisabled('[data-panel="traction"] [data-export="json"]'), false, "the refused request and its problem");
  // a problem no field claims: "see the traction card", never "highlighted"
  await page.fill("#k1", "1");
  await page.evaluate(() => LJApp.showProblem("traction", 422, { title: "Cap exceeded", detail: "the computation hit its cap", errors: [] }));
  assert.equal((await page.textContent("#readout-traction")).match(/hit its cap/g).length, 1, "said once");
});

test("issue 30: the default simulation starts (no 4xx) and its job survives a reload", async () => {
  const api = await (await fetch(`${origin}/openapi.json`)).json();
  if (!(api.paths || {})["/v1/simulations"]) return;
  await page.goto(`${origin}/`); // a fresh page: every field at its default
  await page.waitForSelector("#sim-start");
  const [resp] = await Promise.all([
    page.waitForResponse((r) => r.url().endsWith("/v1/simulations") && r.request().method() === "POST"),
    page.click("#sim-start"),
  ]);
  assert.equal(resp.status(), 202, `the defaults: ${await resp.text()}`);
  const body = JSON.parse(resp.request().postData());
  assert.equal(body.psd.k2, 8);
  const id = (await resp.json()).id;
  assert.match(page.url(), new RegExp(`#job=${id}$`));
  await page.reload();
  // the jobs form is built once /openapi.json has answered: wait for it too
  await page.waitForFunction((i) => { const e = document.getElementById("sim-state"); return e && e.textContent.includes(i.slice(0, 8)); }, id);
  assert.equal(await page.isDisabled("#sim-cancel"), false);
  await page.click("#sim-cancel");
  await page.waitForFunction(() => /cancelled|done/.test(document.getElementById("sim-state").textContent));
  await page.waitForFunction(() => !location.hash);
});

test("issue 30: SI mode with the defaults converts the fields, every request answers 200, the sweep on an SI axis", async () => {
  await page.goto(`${origin}/`); // a fresh page: every field at its default
  await page.waitForSelector("#sim-start");
  await page.check("#do-pdf");
  await page.check("#do-sweep");
  await page.selectOption("#units", "SI"); // switches the material on: SI needs it
  assert.equal(await page.isChecked("#use-material"), true);
  // χ = 3ε²E*/(16Δγ) = 3.375e-10 m, ε = 3e-10 m: k = k̃/χ, C = C̃ ε² χ^(2D−6), m0 = m̃0 ε²
  assert.equal(await page.inputValue("#k1"), "2.96296e9");
  assert.equal(await page.inputValue("#level"), "2.12207e-11");
  assert.match(await page.inputValue("#values"), /^9e-21, 1\.8e-20, 4\.5e-20, /);
  assert.match(await page.textContent("#units-note"), /^In SI now: k1, C, the sweep's values, the table converted with χ = 3\.375e-10 m, ε = 3e-10 m/);
  assert.equal(await page.textContent("#sweep-units"), "(values in m²)");
  const statuses = [];
  const onResp = (r) => r.url().includes("/v1/") && r.request().method() === "POST" && statuses.push(r.status());
  page.on("response", onResp);
  assert.match(await runAndWait("#compute"), /^Done: 3 requests/);
  page.off("response", onResp);
  assert.deepEqual(statuses, [200, 200, 200]);
  const sweep = JSON.parse(await page.evaluate(() => LJApp.panelJSON("sweep")));
  assert.equal(sweep.requests[0].body.units, "SI");
  assert.equal(sweep.requests[0].body.values[0], 9e-21);
  // the same physics as the dimensionless defaults: m̃0 = 0.1 … 10 (Fig. 4's spectrum has m̃0 = 0.5)
  assert.ok(Math.abs(sweep.answers[0].results[2].m0 - 0.5) < 1e-9);
  assert.ok((await inked("plot-sweep")) > 1000, "sweep canvas is blank");
  const f = await page.evaluate(() => LJPlots.figure(document.getElementById("plot-sweep")));
  assert.equal(f.xLabel, "m0 (nm²)");
  assert.ok(f.xLog && Math.abs(f.series[0].x[0] - 0.009) < 1e-12, String(f.series[0].x));
  assert.deepEqual(await page.$$eval("#readout-sweep table tr:first-child th", (t) => t.map((e) => e.textContent)),
    ["m0 (nm²)", "g̃eq (ε)", "σ̄max/σ0", "Δγeff/Δγ", "largest ± err (of the three)", "geq (m)", "σ̄max (Pa)", "Δγeff (J/m²)"]);
  // the sweep's CSV is the server's, in SI
  const [dl] = await Promise.all([page.waitForEvent("download"), page.click('[data-panel="sweep"] [data-export="csv"]')]);
  assert.match(fs.readFileSync(await dl.path(), "utf8"), /^values \[m\^2\],/m);
  // PSD and traction in SI too
  assert.equal((await page.evaluate(() => LJPlots.figure(document.getElementById("plot-psd")))).xLabel, "k (1/m)");
  assert.equal((await page.evaluate(() => LJPlots.figure(document.getElementById("plot-traction")))).xLabel, "gave (m)");
  await page.evaluate(() => document.getElementById("card-sweep").scrollIntoView());
  await page.screenshot({ path: path.join(BUILD, "web-screenshot-si-sweep.png"), fullPage: false });
  // back: the texts from before, exactly
  await page.selectOption("#units", "");
  assert.deepEqual([await page.inputValue("#k1"), await page.inputValue("#level"), await page.inputValue("#values")],
    ["1", "0.0795775", "0.1, 0.2, 0.5, 1, 2, 5, 10"]);
  // a material that is no number: the units stay, the field says why
  await page.fill("#E_star", "soft");
  await page.selectOption("#units", "SI");
  assert.equal(await page.inputValue("#units"), "");
  assert.match(await page.textContent('.err[data-for="units"]'), /give the material's E\*, Δγ and ε as numbers first/);
  await page.fill("#E_star", "1e9");
  await page.uncheck("#use-material");
  await page.uncheck("#do-sweep");
});

test("issue 30: a stored job the server no longer knows is forgotten quietly after a reload", async () => {
  const api = await (await fetch(`${origin}/openapi.json`)).json();
  if (!(api.paths || {})["/v1/simulations"]) return;
  const bogus = "0123456789abcdef0123456789abcdef";
  await page.goto("about:blank");
  // the page's GET answers 404, which Chromium logs as a console error: filed as intended
  await expect4xx(async () => {
    await page.goto(`${origin}/#job=${bogus}`);
    await page.waitForFunction(() => document.getElementById("sim-state") && document.getElementById("sim-state").dataset.status === "gone", null, { timeout: 10000 });
  });
  assert.equal(await page.textContent("#sim-state"), "The job 01234567… from before the reload is no longer known to the server (it may have been restarted); start it again if you need it.");
  assert.equal(page.url(), `${origin}/`, "the id is gone from the URL");
  assert.equal(await page.evaluate(() => localStorage.getItem("ljgap-job")), null);
  assert.equal(await page.isDisabled("#sim-start"), false);
  assert.equal(await page.isDisabled("#sim-cancel"), true);
  assert.equal(await page.evaluate(() => document.getElementById("status").classList.contains("error")), false, "no error styling");
  assert.equal(await page.$$eval("#jobs-card .problem, #jobs-card .invalid", (e) => e.length), 0);
});

test("issue 30: at 390 × 844 the page does not scroll sideways; Compute is on screen", async () => {
  await page.setViewportSize({ width: 390, height: 844 });
  await runAndWait('[data-preset="fig4"]');
  await page.check("#do-pdf");
  await page.check("#do-sweep");
  await runAndWait("#compute-top");
  const w = await page.evaluate(() => [document.documentElement.scrollWidth, document.body.scrollWidth, innerWidth]);
  assert.ok(w[0] <= 390 && w[1] <= 390, `page ${w[0]} px wide at 390`);
  const head = await page.evaluate(() => document.querySelector("header").getBoundingClientRect().height);
  assert.ok(head < 100, `header ${head} px`);
  await page.evaluate(() => window.scrollTo(0, 3000));
  const c = await page.evaluate(() => { const b = document.getElementById("compute-top").getBoundingClientRect(); return [b.top, b.bottom]; });
  assert.ok(c[0] >= 0 && c[1] <= 844, `Compute at ${c}`);
  // every visible input named (a label or aria-label); export buttons named by their card
  const unnamed = await page.evaluate(() => [...document.querySelectorAll("input, select, textarea")]
    .filter((e) => e.offsetParent !== null && !(e.labels && e.labels.length) && !e.getAttribute("aria-label"))
    .map((e) => e.id || e.name));
  assert.deepEqual(unnamed, []);
  const exportNames = await page.$$eval(".exports button", (b) => b.map((e) => e.textContent));
  assert.ok(exportNames.every((t) => /^(Traction|PDF|Sweep|PSD|Pull-off|Simulation|Topography) (CSV|JSON|PNG|Copy as curl)$/.test(t)), exportNames.join("|"));
  // the header's Compute comes first in the focus order (document order, nothing reordered)
  assert.equal(await page.evaluate(() => [...document.querySelectorAll("a[href], button, input, select, textarea")]
    .find((e) => e.offsetParent !== null && !e.disabled).id), "compute-top");
  assert.equal(await page.evaluate(() => document.querySelectorAll("[tabindex]:not([tabindex='-1']):not([tabindex='0'])").length), 0, "no tabindex reorders the page");
  await page.screenshot({ path: path.join(BUILD, "web-screenshot-phone.png"), fullPage: true });
  await page.setViewportSize({ width: 1400, height: 1000 });
});

test("the icon: /favicon.svg linked and served, /favicon.ico served (no 404)", async () => {
  assert.equal(await page.getAttribute('link[rel="icon"]', "href"), "favicon.svg");
  for (const [p, type] of [["/favicon.svg", "image/svg+xml"], ["/favicon.ico", "image/x-icon"]]) {
    const r = await fetch(`${origin}${p}`);
    assert.equal(r.status, 200, p);
    assert.equal(r.headers.get("content-type"), type);
  }
});

test("all panels for the screenshot; no console error at all, no CSP violation, nothing left the server", async () => {
  await page.uncheck("#use-material");
  await runAndWait('[data-preset="fig3"]');
  await page.check("#do-traction");
  await page.check("#do-sweep");
  assert.match(await runAndWait("#compute"), /^Done/);
  await page.evaluate(() => window.scrollTo(0, 0));
  await page.screenshot({ path: path.join(BUILD, "web-screenshot.png"), fullPage: true });
  assert.deepEqual(consoleErrors, []);
  // the refusals provoked on purpose: 422 (a bad field), 404 (a job of another server), 415 (a
  // file of no format the server reads)
  assert.ok(intended.every((t) => / (415|422|404) /.test(t)), String(intended));
  assert.deepEqual(await page.evaluate(() => window.__csp), []);
  assert.deepEqual(foreign, []);
  assert.ok(requests.length > 10);
  for (const u of requests) assert.ok(u.startsWith(origin + "/") || u.startsWith("blob:"), u);
});

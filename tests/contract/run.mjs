// run.mjs -- the contract test: every path, method, status and media type that
// server/openapi.json declares, provoked by a real request to a real ljgapd and checked against
// the document (contract.mjs: status and content type declared, the body against the schema
// for that status and media type, declared headers), then the examples of openapi.json and of
// docs/api.md against live answers. One "ok - ..." / "not ok - ..." line per check; what the
// document declares and no request reached is a "not ok", unless UNREACHABLE below says why it
// cannot be reached honestly on loopback (printed as a "#" line).
//
// Environment (tests/contract/run.sh): URL, PID and ERR of a daemon started with
// --job-workers 1 --job-queue 1 --client-connections 64 (it is stopped by SIGTERM at the end, for
// the 503 of shutdown), WEB_URL of one serving an empty --web directory (the page's 404), MEM_URL
// of one started with --max-memory 64M (the 413 and 503 of the memory budget), ROOT.
import { readFileSync, readdirSync } from "node:fs";
import { setTimeout as sleep } from "node:timers/promises";
import SwaggerParser from "@apidevtools/swagger-parser";
import { fromSchema } from "@openapi-contrib/openapi-schema-to-json-schema";
import * as C from "./contract.mjs";
import { apiExamples, docExamples, fetchExample } from "./examples.mjs";

const { URL: BASE, PID, ERR, WEB_URL, MEM_URL, ROOT = "." } = process.env;
const text = readFileSync(`${ROOT}/server/openapi.json`, "utf8");
let failed = 0;
const report = (ok, what) => {
  if (!ok) failed++;
  console.log(`${ok ? "ok" : "not ok"} - ${what}`);
};

// Declared statuses that no request on loopback can provoke honestly, and why.
const UNREACHABLE = {
  500:
    "out-of-memory is the only 500 of these operations: it needs an allocation to fail, which " +
    "a test cannot cause from outside without faking it (tests/unit inject failed allocations " +
    "into the handler and the job store instead)",
  "DELETE /v1/simulations/{id} 202":
    "a running job sees its cancel within one solver iteration (milliseconds), so DELETE's " +
    "2 s wait always ends with the job stopped (200); 202 needs a job that ignores its cancel " +
    "for 2 s",
};

const api = await (async () => {
  try {
    const a = await C.loadDocument(JSON.parse(text));
    report(true, "server/openapi.json is a valid OpenAPI 3.0 document (swagger-parser)");
    return a;
  } catch (e) {
    report(false, `server/openapi.json is a valid OpenAPI 3.0 document: ${e.message}`);
    process.exit(1);
  }
})();
for (const l of api.lint) report(false, `schema rule: ${l}`);
report(!api.lint.length, "no response schema allows anything (every answer object closed, CSV and HTML with a pattern)");

// ---- every answer goes through check() ----

const covered = new Map(); // "METHOD PATH STATUS [TYPE]" -> count
const problemTypes = new Map(); // type -> set of titles seen

function check(what, method, url, ans, expect = {}) {
  const r = C.checkAnswer(api, method, url, ans);
  const errors = [...r.errors];
  if (expect.status && ans.status !== expect.status) errors.push(`status ${ans.status}, expected ${expect.status}`);
  if (expect.type && r.json?.type !== expect.type) errors.push(`problem type ${r.json?.type}, expected ${expect.type}`);
  if (r.json && /problem/.test(ans.headers["content-type"])) {
    if (!problemTypes.has(r.json.type)) problemTypes.set(r.json.type, new Set());
    problemTypes.get(r.json.type).add(r.json.title);
  }
  if (!r.errors.length) for (const k of r.keys || []) covered.set(k, (covered.get(k) || 0) + 1);
  report(!errors.length, `${r.key || method + " " + url}: ${what}${errors.length ? " -- " + errors.join("; ").slice(0, 600) : ""}`);
  return r;
}

async function call(method, path, opts = {}) {
  try {
    return await C.request(opts.base || BASE, method, path, opts);
  } catch (e) {
    return { status: 0, headers: {}, body: Buffer.from(String(e.message)) };
  }
}

const JSON_CT = { "Content-Type": "application/json" };
const post = (path, body, headers = {}) => call("POST", path, { headers: { ...JSON_CT, ...headers }, body: JSON.stringify(body) });

// ---- requests ----

const PSD = { kind: "power", D: 2.5, k1: 1, m0: 0.5 };
const MAT = { E_star: 1e9, dgamma: 0.05, epsilon: 3e-10 };
// a measured PSD table of P = 1e-30 k^-3.4 (SI), n points at 10 a decade from k0, 10 % errors
const TABLE = (k0, n) => {
  const k = Array.from({ length: n }, (_, i) => k0 * 10 ** (i / 10));
  const P = k.map((x, i) => 1e-30 * x ** -3.4 * (1 + 0.05 * Math.sin(3 * i)));
  return { kind: "table", k, P, P_err: P.map((x) => 0.1 * x) };
};
// A Gwyddion Simple Field of the matrix m (rows of heights in m, spacing 1e-8 m): its header,
// NUL padding to a multiple of 4, then little-endian floats (Gwyddion's user guide, "GSF").
function gsf(m) {
  const ny = m.length, nx = m[0].length;
  let head = `Gwyddion Simple Field 1.0\nXRes = ${nx}\nYRes = ${ny}\nXReal = ${nx * 1e-8}\nYReal = ${ny * 1e-8}\nXYUnits = m\nZUnits = m\n`;
  head += "\0".repeat(4 - (head.length % 4));
  const data = Buffer.alloc(4 * nx * ny);
  m.flat().forEach((v, i) => data.writeFloatLE(v, 4 * i));
  return Buffer.concat([Buffer.from(head, "latin1"), data]);
}
const heights = (nx, ny) =>
  Array.from({ length: ny }, (_, j) => Array.from({ length: nx }, (_, i) => 1e-9 * Math.sin(0.7 * i + 1.3 * j) + 3e-10 * Math.cos(0.31 * i * j)));
const compute = {
  "/v1/adhesion": [
    ["dimensionless", { psd: PSD }],
    ["with a material (si)", { psd: PSD, material: MAT }],
  ],
  "/v1/traction": [
    ["a list of gaps", { psd: PSD, g_ave: [1.5, 2, 3] }],
    ["a range, with a material", { psd: PSD, g_ave: { min: 1.5, max: 5, n: 4 }, material: MAT }],
  ],
  "/v1/pdf": [
    ["two cut-offs, one infinite", { psd: PSD, g_ave: 0.98, k2: [5, null], grid: { min: 0.6, max: 1.6, n: 5 } }],
    ["with a material", { psd: PSD, g_ave: 0.98, k2: [null], grid: { min: 0.6, max: 1.6, n: 5 }, material: MAT }],
  ],
  "/v1/sweep": [
    ["over D", { psd: PSD, vary: "D", values: [2.3, 2.7] }],
    ["over m0, with a material", { psd: PSD, vary: "m0", values: [0.5, 2], material: MAT }],
  ],
  "/v1/contact": [["a sphere", { psd: PSD, material: MAT, R: 1e-6 }]],
  "/v1/psd": [
    ["a height map", { topography: { heights: heights(16, 16), dx: 1e-8 } }],
    ["a profile with a material", { topography: { heights: heights(64, 1), dx: 1e-8 }, material: MAT }],
    ["a periodic map with a material", { topography: { heights: heights(32, 32), dx: 1e-9, periodic: true }, material: MAT }],
  ],
  "/v1/psd/combine": [
    ["two overlapping tables", { psds: [TABLE(1e5, 21), { ...TABLE(1e6, 21), tail: { exponent: -3.4, exponent_err: 0.05 } }] }],
    ["three with a gap, 5 points a decade", { psds: [TABLE(1e5, 6), TABLE(1e6, 11), TABLE(1e8, 6)], points_per_decade: 5 }],
  ],
};
const hasCsv = new Set(["/v1/traction", "/v1/pdf", "/v1/sweep"]);

// ---- 1. the examples ----

async function examples() {
  const ex = [...docExamples(api.doc), ...apiExamples(readFileSync(`${ROOT}/docs/api.md`, "utf8"))];
  for (const e of ex) {
    const live = await fetchExample(BASE, e, call);
    if (e.operation) check(`the example ${e.where} validates`, e.method, live.url || e.path, { ...live, body: Buffer.from(e.text) });
    const r = check(`live answer for the example ${e.where}`, e.method, live.url || e.path, live);
    const diff = e.json !== undefined ? C.compareJson(e.json, r.json, e.volatile) : C.compareCsv(e.text, live.body.toString("utf8"));
    report(live.status === e.status && !diff.length, `the example ${e.where} is the server's answer${live.status !== e.status ? ` -- status ${live.status}, the example ${e.status}` : ""}${diff.length ? " -- " + diff.slice(0, 5).join("; ") : ""}`);
  }
  report(ex.length >= 10, `openapi.json and docs/api.md have examples (${ex.length})`);
}

// ---- 2. the computations ----

async function computations() {
  for (const [path, cases] of Object.entries(compute)) {
    for (const [what, body] of cases) {
      check(what, "POST", path, await post(path, body), { status: 200 });
      if (hasCsv.has(path)) check(`${what}, Accept: text/csv`, "POST", path, await post(path, body, { Accept: "text/csv" }), { status: 200 });
    }
    const ok = cases[0][1];
    check("malformed JSON", "POST", path, await call("POST", path, { headers: JSON_CT, body: '{"psd": ' }), { status: 400, type: "/problems/malformed-json" });
    check("GET", "GET", path, await call("GET", path), { status: 405, type: "/problems/method-not-allowed" });
    check("Accept: application/xml", "POST", path, await post(path, ok, { Accept: "application/xml" }), { status: 406, type: "/problems/not-acceptable" });
    if (hasCsv.has(path) || path === "/v1/adhesion")
      check("Accept: text/csv;q=0, application/json;q=0", "POST", path, await post(path, ok, { Accept: "text/csv;q=0, application/json;q=0" }), { status: 406 });
    check("1.1 MiB sent chunked", "POST", path, await call("POST", path, { headers: JSON_CT, body: JSON.stringify({ pad: "x".repeat(1153434) }), chunked: true }), { status: 413, type: "/problems/content-too-large" });
    check("Content-Type: application/x-www-form-urlencoded", "POST", path, await call("POST", path, { headers: { "Content-Type": "application/x-www-form-urlencoded" }, body: JSON.stringify(ok) }), { status: 415, type: "/problems/unsupported-media-type" });
    check("no psd", "POST", path, await post(path, { tol: -1 }), { status: 422, type: "/problems/validation" });
  }
  // the other kinds of 422, and the text uploads of /v1/psd
  const rows = heights(16, 16).map((r) => r.join(" ")).join("\n") + "\n";
  check("a height matrix as text/plain", "POST", "/v1/psd?dx=1e-8", await call("POST", "/v1/psd?dx=1e-8", { headers: { "Content-Type": "text/plain" }, body: rows }), { status: 200 });
  check("a height matrix as text/csv with a material", "POST", "/v1/psd?dx=1e-8&E_star=1e9&dgamma=0.05&epsilon=3e-10",
    await call("POST", "/v1/psd?dx=1e-8&E_star=1e9&dgamma=0.05&epsilon=3e-10", { headers: { "Content-Type": "text/csv" }, body: rows.replaceAll(" ", ",") }), { status: 200 });
  check("a text upload without dx", "POST", "/v1/psd", await call("POST", "/v1/psd", { headers: { "Content-Type": "text/plain" }, body: rows }), { status: 422 });
  // an instrument file (issue 28): a Gwyddion Simple Field, its grid and size in its header
  const OCTET = { "Content-Type": "application/octet-stream" };
  const file = gsf(heights(24, 16));
  const got = check("an instrument file (GSF) as application/octet-stream", "POST", "/v1/psd?detrend=plane",
    await call("POST", "/v1/psd?detrend=plane", { headers: OCTET, body: file }), { status: 200 });
  report(got.json?.source?.format === "gsf" && got.json?.source?.nx === 24 && Math.abs(got.json?.grid?.dx - 1e-8) < 1e-20,
    `the file's answer names its source and takes its grid (${JSON.stringify(got.json?.source)})`);
  const cut = check("an instrument file cut short", "POST", "/v1/psd", await call("POST", "/v1/psd", { headers: OCTET, body: file.subarray(0, file.length - 5) }),
    { status: 422, type: "/problems/bad-file" });
  report(cut.json?.format === "gsf" && cut.json?.offset === file.length - 5, `bad-file names the format and the offset (${cut.json?.format}, ${cut.json?.offset})`);
  const unknown = check("bytes of no format read here", "POST", "/v1/psd", await call("POST", "/v1/psd", { headers: OCTET, body: Buffer.from("GIF89a\0\0\0\0") }),
    { status: 415, type: "/problems/unsupported-media-type" });
  report(/nanoscope/.test(unknown.json?.detail || ""), "the 415 of an unknown file lists the formats read");
  check("a channel the file does not have", "POST", "/v1/psd?channel=Phase", await call("POST", "/v1/psd?channel=Phase", { headers: OCTET, body: file }), { status: 422, type: "/problems/validation" });
  // a format's own media type is taken like octet-stream (the seed file's short profile has no power-law spectrum: 422 outside-model, not 415)
  const nc = readFileSync(new URL("../fuzz/files_corpus/nc_valid.nc", import.meta.url));
  check("a netCDF file as application/netcdf", "POST", "/v1/psd", await call("POST", "/v1/psd", { headers: { "Content-Type": "application/netcdf" }, body: nc }),
    { status: 422, type: "/problems/outside-model" });
  check("dx beside a file that states its size", "POST", "/v1/psd?dx=1e-9", await call("POST", "/v1/psd?dx=1e-9", { headers: OCTET, body: file }), { status: 422, type: "/problems/validation" });
  // a cached answer (the same request again)
  const body = compute["/v1/adhesion"][0][1];
  const again = check("the same request again (from the cache)", "POST", "/v1/adhesion", await post("/v1/adhesion", body), { status: 200 });
  report(again.json?.meta?.cached === true, "the second identical request is answered from the cache (meta.cached true)");
}

// ---- 2b. the memory budget (a daemon with --max-memory 64M: bodies may hold ~30 MB) ----

async function memory() {
  const big = ("7 ".repeat(49) + "7\n").repeat(400000); // 40 MB of heights
  const TEXT = { "Content-Type": "text/plain" };
  const chunked = check("40 MB chunked, crossing the memory budget", "POST", "/v1/psd?dx=1",
    await call("POST", "/v1/psd?dx=1", { base: MEM_URL, headers: TEXT, body: big, chunked: true }), { status: 503, type: "/problems/busy" });
  report(/--max-memory 64 MiB/.test(chunked.json?.detail || ""), "the 503 of the memory budget names --max-memory");
  // refused from the headers, before the body: the client waits for 100 Continue, so the
  // answer is not lost in a reset while the body is still being written
  const early = (ct, n) => ({ "Content-Type": ct, "Content-Length": String(n), Expect: "100-continue" });
  const sized = check("40 MB with Content-Length, more than the bodies' share", "POST", "/v1/psd?dx=1",
    await call("POST", "/v1/psd?dx=1", { base: MEM_URL, headers: early("text/plain", big.length) }), { status: 413, type: "/problems/content-too-large" });
  report(/--max-memory 64 MiB/.test(sized.json?.detail || ""), "the 413 of the memory budget names --max-memory");
  const grid = check("a simulation whose 512² grid does not fit the budget", "POST", "/v1/simulations",
    await call("POST", "/v1/simulations", { base: MEM_URL, headers: JSON_CT, body: JSON.stringify({ psd: { kind: "power", D: 2.2, k1: 1, k2: 8, m0: 0.1 }, n: 512, realizations: 2, g_ave: [2] }) }), { status: 413 });
  report(/grid/.test(grid.json?.detail || ""), "the simulation's 413 names its grid");
  const png = await call("POST", "/v1/psd", { headers: early("image/png", 2 << 20) });
  check("Content-Type: image/png", "POST", "/v1/psd", png, { status: 415, type: "/problems/unsupported-media-type" });
  report(png.headers?.["accept-post"] === "application/json, text/plain, text/csv, application/octet-stream, application/netcdf, application/x-igor-binary-wave, application/x-sensofar-spm", `/v1/psd's 415 lists the types it takes in Accept-Post (${png.headers?.["accept-post"]})`);
  check("an instrument file over 64 MiB", "POST", "/v1/psd", await call("POST", "/v1/psd", { headers: early("application/octet-stream", (64 << 20) + 1) }),
    { status: 413, type: "/problems/content-too-large" });
}

// ---- 3. the service routes and the page ----

async function service() {
  for (const [path, other] of [["/healthz", "POST"], ["/version", "DELETE"], ["/openapi.json", "PUT"], ["/v1/validity", "POST"], ["/problems/", "POST"]]) {
    check("GET", "GET", path, await call("GET", path), { status: 200 });
    check(other, other, path, await call(other, path), { status: 405 });
  }
  const served = await call("GET", "/openapi.json");
  report(served.body.toString("utf8") === text, "GET /openapi.json is server/openapi.json byte for byte");
  try {
    await SwaggerParser.validate(JSON.parse(served.body.toString("utf8")));
    report(true, "the served document is valid OpenAPI 3.0 (swagger-parser)");
  } catch (e) {
    report(false, `the served document is valid OpenAPI 3.0: ${e.message}`);
  }
  const types = api.deref.components.schemas.Problem.properties.type.enum;
  for (const t of types) check(`the page of ${t}`, "GET", t, await call("GET", t), { status: 200 });
  check("an unknown type", "GET", "/problems/no-such-type", await call("GET", "/problems/no-such-type"), { status: 404 });
  check("POST", "POST", "/problems/validation", await call("POST", "/problems/validation"), { status: 405 });

  // the page and its files, compared with web/
  const files = [
    ["/", "index.html"],
    ...readdirSync(`${ROOT}/web`).filter((f) => /\.(js|css|svg|ico|png|json)$/.test(f) && !/^package/.test(f)).map((f) => [`/${f}`, f]),
    ...readdirSync(`${ROOT}/web/vendor`).map((f) => [`/vendor/${f}`, `vendor/${f}`]),
  ];
  for (const [path, file] of files) {
    const a = await call("GET", path);
    check(`web/${file}`, "GET", path, a, { status: 200 });
    report(a.body.equals(readFileSync(`${ROOT}/web/${file}`)), `GET ${path} is web/${file} byte for byte`);
    check(`web/${file} with its ETag`, "GET", path, await call("GET", path, { headers: { "If-None-Match": a.headers.etag || '"none"' } }), { status: 304 });
    check("POST", "POST", path, await call("POST", path), { status: 405 });
  }
  for (const path of ["/nothing.js", "/vendor/nothing.css"]) check("a file the page does not have", "GET", path, await call("GET", path), { status: 404 });
  check("--web DIR without index.html", "GET", "/", await call("GET", "/", { base: WEB_URL }), { status: 404 });

  // a path the document does not have: a 404 problem all the same
  const nope = await call("GET", "/v2/nothing");
  const p = api.validators.get("GET /v1/simulations/{id} 404 application/problem+json");
  report(nope.status === 404 && p(JSON.parse(nope.body.toString("utf8") || "null")), "GET /v2/nothing (no such path): 404 problem");
}

// ---- 4. simulation jobs ----

const SIM_PSD = { kind: "power", D: 2.5, k1: 1, k2: 4, m0: 0.5 };
const LONG = { psd: SIM_PSD, g_ave: { min: 1.5, max: 6, n: 200 }, n: 256, realizations: 16, tol: 1e-14 };

async function waitJob(id, done) {
  for (let i = 0; i < 300; i++) {
    const a = await call("GET", `/v1/simulations/${id}`);
    const j = a.status === 200 ? JSON.parse(a.body.toString("utf8")) : null;
    if (!j || done(j)) return a;
    await sleep(50);
  }
  return call("GET", `/v1/simulations/${id}`);
}

async function simulations() {
  const P = "/v1/simulations";
  for (const [what, body, status] of [
    ["malformed JSON", "{", 400],
    ["an unknown field", JSON.stringify({ psd: SIM_PSD, g_ave: [2], method: "pde" }), 422],
  ])
    check(what, "POST", P, await call("POST", P, { headers: JSON_CT, body }), { status });
  check("GET", "GET", P, await call("GET", P), { status: 405 });
  check("1.1 MiB sent chunked", "POST", P, await call("POST", P, { headers: JSON_CT, body: JSON.stringify({ pad: "x".repeat(1153434) }), chunked: true }), { status: 413 });
  check("Content-Type: text/plain", "POST", P, await call("POST", P, { headers: { "Content-Type": "text/plain" }, body: "{}" }), { status: 415 });

  // a small job, done: its status as JSON and its result as CSV
  const small = check("a small job", "POST", P, await post(P, { psd: SIM_PSD, g_ave: [2, 3], n: 8, realizations: 2 }), { status: 202 });
  const id = small.json?.id;
  const done = await waitJob(id, (j) => j.status === "done" || j.status === "failed");
  check("the small job, done", "GET", `${P}/${id}`, done, { status: 200 });
  check("the small job's result as CSV", "GET", `${P}/${id}`, await call("GET", `${P}/${id}`, { headers: { Accept: "text/csv" } }), { status: 200 });
  // a hybrid job (k_split): its result has k_split and the fine band
  const hyb = check("a hybrid job", "POST", P, await post(P, { psd: { ...SIM_PSD, k2: 8 }, g_ave: [2, 3], n: 8, realizations: 1, k_split: 3 }), { status: 202 }).json?.id;
  const hdone = check("the hybrid job, done", "GET", `${P}/${hyb}`, await waitJob(hyb, (j) => j.status === "done" || j.status === "failed"), { status: 200 });
  report(hdone.json?.result?.fine && hdone.json.result.k_split === 3, "the hybrid job's result has k_split and fine");
  check("the hybrid job's result as CSV", "GET", `${P}/${hyb}`, await call("GET", `${P}/${hyb}`, { headers: { Accept: "text/csv" } }), { status: 200 });
  check("Accept: application/xml", "GET", `${P}/${id}`, await call("GET", `${P}/${id}`, { headers: { Accept: "application/xml" } }), { status: 406 });
  check("DELETE a done job", "DELETE", `${P}/${id}`, await call("DELETE", `${P}/${id}`), { status: 200 });
  check("PUT", "PUT", `${P}/${id}`, await call("PUT", `${P}/${id}`), { status: 405 });
  const unknown = "0123456789abcdef0123456789abcdef";
  check("an unknown id", "GET", `${P}/${unknown}`, await call("GET", `${P}/${unknown}`), { status: 404 });
  check("an unknown id", "DELETE", `${P}/${unknown}`, await call("DELETE", `${P}/${unknown}`), { status: 404 });

  // one long job running, one queued (--job-queue 1), a third refused
  const a = check("a long job", "POST", P, await post(P, LONG), { status: 202 }).json?.id;
  check("the long job, running", "GET", `${P}/${a}`, await waitJob(a, (j) => j.status === "running"), { status: 200 });
  const b = check("a second job, queued", "POST", P, await post(P, { ...LONG, seed: 2 }), { status: 202 }).json?.id;
  check("a third job, the queue full", "POST", P, await post(P, { ...LONG, seed: 3 }), { status: 503, type: "/problems/busy" });
  check("Accept: text/csv for a queued job (no CSV yet)", "GET", `${P}/${b}`, await call("GET", `${P}/${b}`, { headers: { Accept: "text/csv" } }), { status: 406 });
  check("DELETE the queued job", "DELETE", `${P}/${b}`, await call("DELETE", `${P}/${b}`), { status: 200 });
  check("the cancelled job", "GET", `${P}/${b}`, await call("GET", `${P}/${b}`), { status: 200 });
  return a; // left running for the shutdown
}

// ---- 5. shutdown: every offloaded route answers 503 while the daemon stops ----
// Connections idle at SIGTERM are closed, so each request is sent but for its last two bytes
// before the signal and finished after it; one more, whose body never ends, keeps the daemon in
// its stop (it waits up to 10 s for requests in flight) until the checks are done.

async function shutdown(longJob) {
  const targets = [
    // a space after the JSON: not the cached answer of the same request, a computation
    ...Object.keys(compute).map((p) => ["POST", p, { headers: JSON_CT, body: JSON.stringify(compute[p][0][1]) + " " }]),
    ["POST", "/v1/simulations", { headers: JSON_CT, body: JSON.stringify({ psd: SIM_PSD, g_ave: [2], n: 8 }) }],
    ["GET", `/v1/simulations/${longJob}`, {}],
    ["DELETE", `/v1/simulations/${longJob}`, {}],
  ];
  const TRIES = 2; // a request that came before the stop reached its pool is tried again
  const prepared = [];
  for (const [method, path, opts] of targets) {
    for (let t = 0; t < TRIES; t++) {
      const sock = await C.connect(BASE);
      const bytes = C.requestBytes(BASE, method, path, opts);
      sock.write(bytes.subarray(0, bytes.length - 2));
      prepared.push({ method, path, sock, rest: bytes.subarray(bytes.length - 2) });
    }
  }
  const hold = await C.connect(BASE);
  hold.write(Buffer.concat([C.requestBytes(BASE, "POST", "/v1/adhesion", { headers: { ...JSON_CT, "Content-Length": "100" } }), Buffer.from("{")]));
  await sleep(100);
  process.kill(Number(PID), "SIGTERM");
  let line = "";
  for (let i = 0; i < 100 && !line; i++) {
    line = readFileSync(ERR, "utf8").split("\n").find((l) => /stopping \(\d+ requests in flight\)/.test(l)) || "";
    if (!line) await sleep(20);
  }
  report(/\(([1-9]\d*) requests in flight\)/.test(line), `SIGTERM with requests in flight: ${line || "no stopping line"}`);
  await sleep(100);
  for (const [method, path] of targets) {
    let got = null;
    for (const p of prepared.filter((x) => x.method === method && x.path === path)) {
      if (got && got.status === 503) break;
      try {
        const answer = C.readAnswer(p.sock, 10000);
        p.sock.write(p.rest);
        got = await answer;
      } catch (e) {
        got = { status: 0, headers: {}, body: Buffer.from(e.message) };
      }
    }
    check("while the server shuts down", method, path, got, { status: 503 });
  }
  hold.destroy();
  prepared.forEach((p) => p.sock.destroy());
}

// ---- run ----

await examples();
await computations();
await memory();
await service();
const longJob = await simulations();
await shutdown(longJob);

for (const [type, titles] of problemTypes) report(titles.size === 1, `problems of type ${type} have one title (${[...titles].join(" | ")})`);

// what the document declares and no request reached
for (const o of api.ops) {
  for (const [status, resp] of Object.entries(o.op.responses)) {
    const keys = status === "304" ? [`${o.method} ${o.path} 304`] : Object.keys(resp.content || {}).map((t) => `${o.method} ${o.path} ${status} ${t}`);
    for (const k of keys) {
      const why = UNREACHABLE[`${o.method} ${o.path} ${status}`] || UNREACHABLE[status];
      if (covered.has(k)) report(!why, `${k} reached${why ? " (listed as unreachable: remove it from UNREACHABLE)" : ""}`);
      else if (why) console.log(`# ${k}: not reached: ${why}`);
      else report(false, `${k} declared and reached by no request`);
    }
  }
}
console.log(`# ${failed} failed`);
process.exit(failed ? 1 : 0);

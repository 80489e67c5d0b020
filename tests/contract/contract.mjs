// contract.mjs -- what the contract test and the example writer share: the OpenAPI document
// checked and made into validators, an answer checked against it, a raw HTTP client, and the
// comparison of an example with a live answer.
//
// The document is validated against the OpenAPI 3.0 schema by @apidevtools/swagger-parser and
// dereferenced by it. Each response schema is converted from an OpenAPI 3.0 Schema Object to
// JSON Schema (draft 4, which keeps 3.0's boolean exclusiveMinimum/exclusiveMaximum) by
// @openapi-contrib/openapi-schema-to-json-schema (nullable: true becomes a "null" type, and is
// ignored without a type, as 3.0.3 says; discriminator and example are dropped), and compiled
// by ajv (ajv-draft-04, with ajv-formats for date-time).
//
// The rule for schemas that allow anything (lintDocument): every response has content with a
// schema per media type, except 304, which has no content; in a JSON answer every object is
// closed (additionalProperties false, or a schema for maps whose keys are data), no schema is
// empty or open ({}, additionalProperties: true, a bare type object); CSV and HTML answers are
// strings with a pattern (the CSV's header line, the HTML doctype); the page's scripts, styles
// and icons are strings compared byte for byte with web/. One exemption, named in EXEMPT: the
// document itself (GET /openapi.json), whose schema is the OpenAPI Specification's own and is
// checked with swagger-parser instead.
import SwaggerParser from "@apidevtools/swagger-parser";
import { fromSchema } from "@openapi-contrib/openapi-schema-to-json-schema";
import Ajv from "ajv-draft-04";
import addFormats from "ajv-formats";
import net from "node:net";

export const METHODS = ["get", "put", "post", "delete", "patch", "head", "options"];
const JSON_TYPE = /^application\/(.+\+)?json$/;
// media type -> why it is not held to the closed-object rule
const EXEMPT = {
  "GET /openapi.json 200 application/json":
    "the document itself: validated against the OpenAPI 3.0 schema by swagger-parser",
};

// ---- the document ----

// Validates doc (a parsed openapi.json) and returns {doc, deref, ops, validators, lint}.
// ops: [{path, method, op, re, params}] with concrete paths before templated ones.
export async function loadDocument(doc) {
  await SwaggerParser.validate(structuredClone(doc));
  const deref = await SwaggerParser.dereference(structuredClone(doc));
  const ajv = new Ajv({ allErrors: true, strict: true, allowUnionTypes: true });
  addFormats(ajv);
  ajv.addFormat("binary", true); // image bytes: compared with the files instead
  const ops = [];
  for (const [path, item] of Object.entries(deref.paths)) {
    for (const method of METHODS) {
      if (!item[method]) continue;
      const params = [...(item.parameters || []), ...(item[method].parameters || [])].filter(
        (p) => p.in === "path",
      );
      const re = new RegExp(
        "^" + path.replace(/[.*+?^$()|[\]\\]/g, "\\$&").replace(/\\?\{([^}]+)\\?\}/g, "(?<$1>[^/]+)") + "$",
      );
      ops.push({ path, method: method.toUpperCase(), op: item[method], re, params, templated: path.includes("{") });
    }
  }
  ops.sort((a, b) => a.templated - b.templated);
  const validators = new Map();
  const lint = [];
  for (const o of ops) {
    for (const [status, resp] of Object.entries(o.op.responses)) {
      const where = `${o.method} ${o.path} ${status}`;
      if (status === "304") {
        if (resp.content) lint.push(`${where}: a 304 has no content`);
        continue;
      }
      if (!resp.content || !Object.keys(resp.content).length) {
        lint.push(`${where}: no content declared`);
        continue;
      }
      for (const [type, media] of Object.entries(resp.content)) {
        if (!media.schema) {
          lint.push(`${where} ${type}: no schema`);
          continue;
        }
        lintRequired(media.schema, `${where} ${type}`, lint);
        const schema = fromSchema(media.schema);
        if (!EXEMPT[`${where} ${type}`]) lintSchema(schema, `${where} ${type}`, type, lint);
        validators.set(`${where} ${type}`, ajv.compile(schema));
      }
    }
  }
  for (const [name, h] of Object.entries(deref.components.headers || {}))
    validators.set(`header ${name}`, ajv.compile(fromSchema(h.schema)));
  return { doc, deref, ops, validators, lint, ajv };
}

// Every required member is declared (the converter drops the others without a word).
function lintRequired(s, where, out, seen = new Set()) {
  if (!s || typeof s !== "object" || seen.has(s)) return;
  seen.add(s);
  for (const k of s.required || []) if (s.properties && !(k in s.properties)) out.push(`${where}: ${k} required, not declared`);
  for (const v of Object.values(s)) if (v && typeof v === "object") lintRequired(v, where, out, seen);
}

const CONSTRAINTS = ["type", "enum", "oneOf", "anyOf", "allOf", "not", "pattern", "properties", "items"];

// The closed-schema rule above, on a converted (JSON Schema) schema.
function lintSchema(s, where, mediaType, out, at = "") {
  if (!s || typeof s !== "object") return;
  const here = `${where}${at ? " at " + at : ""}`;
  if (!CONSTRAINTS.some((k) => k in s)) out.push(`${here}: the schema allows anything`);
  const types = [].concat(s.type || []);
  if (at === "" && !JSON_TYPE.test(mediaType)) {
    if (!types.includes("string")) out.push(`${here}: a ${mediaType} answer is not a string`);
    if (/^text\/(csv|html)$/.test(mediaType) && !s.pattern)
      out.push(`${here}: a ${mediaType} answer needs a pattern (its header line, its doctype)`);
  }
  if ((types.includes("object") || s.properties) && !s.enum) {
    if (s.additionalProperties === undefined || s.additionalProperties === true)
      out.push(`${here}: an object left open (additionalProperties not false, nor a schema)`);
  }
  for (const [k, v] of Object.entries(s.properties || {})) lintSchema(v, where, mediaType, out, `${at}/${k}`);
  if (typeof s.additionalProperties === "object") lintSchema(s.additionalProperties, where, mediaType, out, `${at}/*`);
  if (s.items) lintSchema(s.items, where, mediaType, out, `${at}[]`);
  for (const k of ["oneOf", "anyOf", "allOf"])
    (s[k] || []).forEach((v, i) => lintSchema(v, where, mediaType, out, `${at}(${k}${i})`));
}

// The operation of method on url's path: {o, params}; for a method the path does not have,
// {path, others} (the path's operations); null for a path the document does not have.
export function findOperation(api, method, url) {
  const path = url.split("?")[0];
  let others = null;
  for (const o of api.ops) {
    const m = o.re.exec(path);
    if (!m) continue;
    const params = m.groups || {};
    const fits = o.params.every((p) => {
      const v = api.ajv.compile(fromSchema(p.schema));
      return v(decodeURIComponent(params[p.name] ?? ""));
    });
    if (!fits) continue;
    if (o.method === method) return { o, params };
    others = others || { path: o.path, others: [] };
    if (others.path === o.path) others.others.push(o);
  }
  return others;
}

// ---- checking an answer ----

function mediaOf(ct) {
  return (ct || "").split(";")[0].trim().toLowerCase();
}

// Checks one answer {status, headers, body (Buffer)} to method url against the document.
// Returns {errors: [...], key: "METHOD PATH STATUS TYPE", keys (what it covered: the key, or for
// a 405 the same of every operation of the path), json}.
export function checkAnswer(api, method, url, ans) {
  const errors = [];
  const found = findOperation(api, method, url);
  let op, also = [];
  if (!found) return { errors: [`${method} ${url}: the path is not in the document`] };
  if (found.o) {
    op = found.o;
  } else {
    // a method the path does not have: its 405 must be declared by every operation of the path
    const missing = found.others.filter((o) => !o.op.responses[String(ans.status)]);
    if (ans.status !== 405) errors.push(`${method} ${found.path}: answered ${ans.status}, not 405`);
    if (missing.length)
      errors.push(`${found.path}: ${missing.map((o) => o.method).join(", ")} do not declare ${ans.status}`);
    [op, ...also] = found.others;
  }
  const status = String(ans.status);
  const resp = op.op.responses[status];
  const key0 = `${op.method} ${op.path} ${status}`;
  if (!resp) return { errors: [...errors, `${key0}: status not declared`], key: key0 };
  for (const [name, h] of Object.entries(resp.headers || {})) {
    const v = ans.headers[name.toLowerCase()];
    if (v === undefined) {
      if (h.required) errors.push(`${key0}: header ${name} missing`);
      continue;
    }
    const val = /^-?[0-9]+$/.test(v) && ["integer", "number"].includes(h.schema.type) ? Number(v) : v;
    const hv = api.validators.get(`header ${name}`) || api.ajv.compile(fromSchema(h.schema));
    if (!hv(val)) errors.push(`${key0}: header ${name}: ${JSON.stringify(v)} ${api.ajv.errorsText(hv.errors)}`);
  }
  if (status === "304") {
    if (ans.body.length) errors.push(`${key0}: a 304 with a body`);
    return { errors, key: key0, keys: [key0] };
  }
  const type = mediaOf(ans.headers["content-type"]);
  const key = `${key0} ${type}`;
  const keys = [key, ...also.map((o) => `${o.method} ${o.path} ${status} ${type}`)];
  const validate = api.validators.get(key);
  if (!validate) return { errors: [...errors, `${key}: content type not declared`], key, keys };
  let value = ans.body;
  let json;
  if (JSON_TYPE.test(type)) {
    try {
      json = value = JSON.parse(ans.body.toString("utf8"));
    } catch (e) {
      return { errors: [...errors, `${key}: not JSON (${e.message})`], key, keys };
    }
  } else if (!/^image\/(?!svg)/.test(type)) {
    value = ans.body.toString("utf8");
  } else {
    value = ans.body.toString("base64");
  }
  if (!validate(value)) errors.push(`${key}: ${api.ajv.errorsText(validate.errors, { separator: "; " })}`);
  if (type === "application/problem+json" && json && json.status !== ans.status)
    errors.push(`${key}: the problem's status ${json.status} is not the answer's`);
  if (type === "text/csv") errors.push(...checkCsv(value).map((e) => `${key}: ${e}`));
  return { errors, key, keys, json };
}

// A CSV answer is rectangular: every row has as many cells as the header line.
function checkCsv(text) {
  const lines = text.split("\n").filter((l) => l !== "" && !l.startsWith("#"));
  const n = lines.length ? lines[0].split(",").length : 0;
  const bad = lines.findIndex((l) => l.split(",").length !== n);
  return bad < 0 ? [] : [`row ${bad} has ${lines[bad].split(",").length} cells, the header ${n}`];
}

// ---- raw HTTP (one request per connection unless a socket is given) ----

// Reads one answer from sock: {status, headers, body}. Rejects on close before it is whole.
export function readAnswer(sock, timeoutMs = 30000) {
  return new Promise((resolve, reject) => {
    let buf = Buffer.alloc(0);
    const done = (f, v) => {
      clearTimeout(timer);
      sock.off("data", onData);
      sock.off("close", onClose);
      sock.off("error", onClose);
      f(v);
    };
    const timer = setTimeout(() => done(reject, new Error("no answer in time")), timeoutMs);
    const onData = (d) => {
      buf = Buffer.concat([buf, d]);
      const end = buf.indexOf("\r\n\r\n");
      if (end < 0) return;
      const lines = buf.subarray(0, end).toString("latin1").split("\r\n");
      const status = Number(lines[0].split(" ")[1]);
      const headers = {};
      for (const l of lines.slice(1)) {
        const i = l.indexOf(":");
        const k = l.slice(0, i).trim().toLowerCase();
        if (!(k in headers)) headers[k] = l.slice(i + 1).trim();
      }
      const len = status === 304 ? 0 : Number(headers["content-length"] ?? NaN);
      if (!(len >= 0)) return done(reject, new Error("no Content-Length"));
      if (buf.length < end + 4 + len) return;
      done(resolve, { status, headers, body: buf.subarray(end + 4, end + 4 + len) });
    };
    const onClose = (e) => done(reject, e instanceof Error ? e : new Error("closed before the answer"));
    sock.on("data", onData);
    sock.on("close", onClose);
    sock.on("error", onClose);
  });
}

export function connect(base) {
  const u = new URL(base);
  return new Promise((resolve, reject) => {
    const s = net.connect({ host: u.hostname, port: Number(u.port) }, () => resolve(s));
    s.once("error", reject);
  });
}

// The bytes of a request. body: string or Buffer; chunked: send it in chunks, no length.
export function requestBytes(base, method, path, { headers = {}, body, chunked = false } = {}) {
  const u = new URL(base);
  const h = { Host: u.host, ...headers };
  const b = body === undefined ? null : Buffer.from(body);
  if (b && chunked) h["Transfer-Encoding"] = "chunked";
  else if (b) h["Content-Length"] = String(b.length);
  const head = `${method} ${path} HTTP/1.1\r\n` + Object.entries(h).map(([k, v]) => `${k}: ${v}\r\n`).join("") + "\r\n";
  if (!b) return Buffer.from(head);
  if (!chunked) return Buffer.concat([Buffer.from(head), b]);
  const parts = [Buffer.from(head)];
  for (let i = 0; i < b.length; i += 65536) {
    const c = b.subarray(i, i + 65536);
    parts.push(Buffer.from(c.length.toString(16) + "\r\n"), c, Buffer.from("\r\n"));
  }
  parts.push(Buffer.from("0\r\n\r\n"));
  return Buffer.concat(parts);
}

// One request on a new connection (or on sock, left open): {status, headers, body}.
export async function request(base, method, path, opts = {}) {
  const sock = opts.socket || (await connect(base));
  try {
    const answer = readAnswer(sock, opts.timeoutMs);
    sock.write(requestBytes(base, method, path, opts));
    return await answer;
  } finally {
    if (!opts.socket) sock.destroy();
  }
}

// ---- examples ----

// Members whose values differ from one run to the next: compared by presence and type only.
export const VOLATILE = new Set(["elapsed_ms", "id", "created", "started", "finished", "cached"]);
const REL = 1e-9; // numbers: relative difference allowed (printing and build differences)

function close(a, b) {
  return a === b || Math.abs(a - b) <= REL * Math.max(Math.abs(a), Math.abs(b));
}

// Differences between an example and a live answer (JSON values), as "path: ..." strings. A
// volatile member may also be missing from the example (a job that ran before its 202 was
// written has started, finished and result already).
export function compareJson(want, got, volatile = VOLATILE, at = "") {
  const out = [];
  const name = at.split("/").pop();
  if (volatile.has(name)) {
    if (typeof want !== typeof got) out.push(`${at}: ${typeof got}, the example has ${typeof want}`);
    return out;
  }
  if (typeof want === "number" && typeof got === "number") {
    if (!close(want, got)) out.push(`${at}: ${got}, the example has ${want}`);
  } else if (Array.isArray(want) && Array.isArray(got)) {
    if (want.length !== got.length) out.push(`${at}: ${got.length} items, the example has ${want.length}`);
    else want.forEach((w, i) => out.push(...compareJson(w, got[i], volatile, `${at}/${i}`)));
  } else if (want && got && typeof want === "object" && typeof got === "object" && !Array.isArray(want) && !Array.isArray(got)) {
    const keys = new Set([...Object.keys(want), ...Object.keys(got)]);
    for (const k of keys) {
      if (!(k in got)) out.push(`${at}/${k}: missing from the answer`);
      else if (!(k in want)) {
        if (!volatile.has(k)) out.push(`${at}/${k}: not in the example`);
      }
      else out.push(...compareJson(want[k], got[k], volatile, `${at}/${k}`));
    }
  } else if (want !== got) {
    out.push(`${at}: ${JSON.stringify(got)}, the example has ${JSON.stringify(want)}`);
  }
  return out;
}

// The same for CSV text: line by line, cell by cell (numbers with the tolerance), the lines
// of volatile fields (# ...elapsed_ms [ms] = ..., # ...cached = ...) by their names only.
export function compareCsv(want, got) {
  const w = want.split("\n"), g = got.split("\n");
  if (w.length !== g.length) return [`${g.length} lines, the example has ${w.length}`];
  const out = [];
  const cells = (l) => l.split(/(,| = | ± )/);
  w.forEach((wl, i) => {
    const vol = /^# (\S+\.)?(\w+)( \[[^\]]*\])? = /.exec(wl);
    if (vol && VOLATILE.has(vol[2])) {
      if (!g[i].startsWith(wl.slice(0, vol[0].length))) out.push(`line ${i + 1}: ${g[i]}`);
      return;
    }
    const a = cells(wl), b = cells(g[i]);
    const same =
      a.length === b.length &&
      a.every((x, k) => x === b[k] || (x !== "" && b[k] !== "" && !isNaN(x) && !isNaN(b[k]) && close(Number(x), Number(b[k]))));
    if (!same) out.push(`line ${i + 1}: ${JSON.stringify(g[i])}, the example has ${JSON.stringify(wl)}`);
  });
  return out;
}

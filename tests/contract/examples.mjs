// examples.mjs -- the examples of server/openapi.json and docs/api.md, which are live answers.
//
//   node tests/contract/examples.mjs URL     rewrite them from the answers of the ljgapd at URL
//                                            (components/examples of openapi.json, the answer
//                                            blocks of api.md); the contract test (run.mjs)
//                                            compares them with live answers in make test
//
// openapi.json: an answer example NAME of an operation (content.TYPE.examples.NAME, a $ref into
// components/examples) answers that operation's request example of the same NAME, sent with
// Accept: TYPE; GET /v1/simulations/{id}'s examples are the job that POST /v1/simulations's
// example of that name starts, polled until it is done. docs/api.md: every ```sh block running
// curl on localhost:8080 is followed by a fenced block holding the answer's body.
// Members that change from run to run (contract.mjs VOLATILE: elapsed_ms, id, times, cached; and
// a new job's status and progress) are compared by their type only; numbers to 1e-9 relative.
import { readFileSync, writeFileSync } from "node:fs";
import { setTimeout as sleep } from "node:timers/promises";
import { fileURLToPath } from "node:url";
import { VOLATILE, request } from "./contract.mjs";

const deref = (doc, x) => {
  while (x && x.$ref) x = x.$ref.slice(2).split("/").reduce((o, k) => o[k], doc);
  return x;
};

// [{where, method, path, status, type, request, json | text, volatile, ref}] of openapi.json
export function docExamples(doc) {
  const out = [];
  const requests = (path, method) => {
    const rb = deref(doc, doc.paths[path]?.[method]?.requestBody);
    const ex = rb?.content?.["application/json"]?.examples || {};
    return Object.fromEntries(Object.entries(ex).map(([k, v]) => [k, deref(doc, v).value]));
  };
  for (const [path, item] of Object.entries(doc.paths)) {
    for (const [method, op] of Object.entries(item)) {
      if (method === "parameters") continue;
      for (const [status, r] of Object.entries(op.responses)) {
        for (const [type, media] of Object.entries(deref(doc, r).content || {})) {
          for (const [name, ex] of Object.entries(media.examples || {})) {
            const from = path === "/v1/simulations/{id}" ? requests("/v1/simulations", "post") : requests(path, method);
            const value = deref(doc, ex).value;
            const isText = /^text\//.test(type);
            // a new job may be queued, running or done already when its 202 is written
            const volatile = status === "202" ? new Set([...VOLATILE, "status", "progress", "result"]) : VOLATILE;
            out.push({
              where: `openapi.json ${method.toUpperCase()} ${path} ${status} ${type} "${name}"`,
              method: method.toUpperCase(), path, status: Number(status), type, name,
              request: from[name], ref: ex.$ref, volatile,
              ...(isText ? { text: value } : { json: value, text: JSON.stringify(value) }),
            });
          }
        }
      }
    }
  }
  return out;
}

// The arguments of a shell command line of single-quoted or bare words.
function words(line) {
  return [...line.matchAll(/'([^']*)'|(\S+)/g)].map((m) => m[1] ?? m[2]);
}

// [{where, method, path, status, headers, body, json | text, block}] of docs/api.md
export function apiExamples(md) {
  const out = [];
  const re = /^```sh\n((?:(?!```)[\s\S])*?curl[^\n]*localhost:8080(?:(?!```)[\s\S])*?)^```\n\s*^```(\w+)\n([\s\S]*?)^```$/gm;
  let m, n = 0;
  while ((m = re.exec(md))) {
    const w = words(m[1].replace(/\\\n/g, " ").trim());
    const e = { method: "GET", headers: {}, lang: m[2], block: m[3], offset: m.index + m[0].length - m[3].length - 3 }; // where the answer block's text starts
    for (let i = 1; i < w.length; i++) {
      if (w[i] === "-X") e.method = w[++i];
      else if (w[i] === "-H") {
        const [k, ...v] = w[++i].split(":");
        e.headers[k] = v.join(":").trim();
      } else if (w[i] === "-d" || w[i] === "--data-binary") {
        e.body = w[++i];
        if (e.method === "GET") e.method = "POST";
      } else if (/localhost:8080/.test(w[i])) e.path = w[i].replace(/^(https?:\/\/)?localhost:8080/, "");
    }
    n++;
    if (e.lang === "json") {
      e.json = JSON.parse(m[3]);
      e.text = JSON.stringify(e.json);
      e.status = /^\/problems\//.test(e.json.type || "") ? e.json.status : 200;
    } else {
      e.text = m[3];
      e.status = 200;
    }
    e.where = `docs/api.md #${n} (${e.method} ${e.path})`;
    e.volatile = VOLATILE;
    out.push(e);
  }
  return out;
}

// The live answer to example e: {status, headers, body, url}.
export async function fetchExample(base, e, call = (m, p, o) => request(base, m, p, o)) {
  const json = { "Content-Type": "application/json" };
  if (e.headers) return { ...(await call(e.method, e.path, { headers: e.headers, body: e.body })), url: e.path };
  if (!e.request) return { status: 0, headers: {}, body: Buffer.from(`no request example "${e.name}"`) };
  const body = JSON.stringify(e.request);
  if (e.path !== "/v1/simulations/{id}")
    return { ...(await call(e.method, e.path, { headers: { ...json, Accept: e.type }, body })), url: e.path };
  const started = await call("POST", "/v1/simulations", { headers: json, body });
  const id = JSON.parse(started.body.toString("utf8") || "{}").id;
  const url = `/v1/simulations/${id}`;
  for (let i = 0; i < 600; i++) {
    const a = await call("GET", url);
    if (a.status !== 200 || !["queued", "running"].includes(JSON.parse(a.body.toString("utf8")).status)) break;
    await sleep(50);
  }
  return { ...(await call("GET", url, { headers: { Accept: e.type } })), url };
}

// ---- writing them ----

async function write(base, root) {
  const docPath = `${root}/server/openapi.json`;
  const text = readFileSync(docPath, "utf8");
  const doc = JSON.parse(text);
  for (const e of docExamples(doc)) {
    const live = await fetchExample(base, e);
    if (live.status !== e.status) throw new Error(`${e.where}: the server answered ${live.status}`);
    const body = live.body.toString("utf8");
    deref(doc, { $ref: e.ref }).value = e.json !== undefined ? JSON.parse(body) : body;
  }
  const at = text.indexOf('\n    "examples": {');
  if (at < 0) throw new Error("openapi.json: components/examples must be the last member of components");
  const lines = Object.entries(doc.components.examples).map(([k, v]) => `      ${JSON.stringify(k)}: ${JSON.stringify(v)}`);
  writeFileSync(docPath, text.slice(0, at) + '\n    "examples": {\n' + lines.join(",\n") + "\n    }\n  }\n}\n");

  const mdPath = `${root}/docs/api.md`;
  let md = readFileSync(mdPath, "utf8");
  const ex = apiExamples(md).reverse(); // from the end, so that offsets hold
  for (const e of ex) {
    const live = await fetchExample(base, e);
    let body = live.body.toString("utf8");
    if (e.lang === "json") body = JSON.stringify(JSON.parse(body), null, 2) + "\n";
    md = md.slice(0, e.offset) + body + md.slice(e.offset + e.block.length);
  }
  writeFileSync(mdPath, md);
}

if (process.argv[1] === fileURLToPath(import.meta.url)) {
  const root = fileURLToPath(new URL("../..", import.meta.url));
  await write(process.argv[2], root);
}

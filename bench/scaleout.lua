-- scaleout.lua -- wrk script of bench/scaleout.sh: POST /v1/adhesion with a request that no
-- earlier one repeated (its tol is the given one times 1 + a per-thread, per-request term of
-- order 1e-9: the same computation, missing every instance's answer cache), and a tally of the
-- answers by status and of cache hits (wrk itself only counts "non-2xx or 3xx").
--   wrk -s bench/scaleout.lua URL -- TOL
local json = { ["Content-Type"] = "application/json" }
local threads = {}

function setup(thread)
    thread:set("id", #threads)
    table.insert(threads, thread)
end

function init(args)
    tol = tonumber(args[1]) or 1e-6
    run = tonumber(args[2]) or 0
    n = 0
    counts = {}
    hits = 0
end

function request()
    n = n + 1
    local t = tol * (1 + ((run * 4 + id) * 1e6 + n) * 1e-13)
    return wrk.format("POST", "/v1/adhesion", json,
        string.format('{"psd":{"kind":"power","D":2.5,"k1":1,"C":0.0796},"tol":%.17g}', t))
end

function response(status, headers, body)
    counts[status] = (counts[status] or 0) + 1
    if body:find('"cached":true', 1, true) then hits = hits + 1 end
end

function done(summary, latency, requests)
    local total, keys, h = {}, {}, 0
    for _, t in ipairs(threads) do
        for s, c in pairs(t:get("counts")) do total[s] = (total[s] or 0) + c end
        h = h + t:get("hits")
    end
    for s in pairs(total) do table.insert(keys, s) end
    table.sort(keys)
    for _, s in ipairs(keys) do io.write(string.format("status %d %d\n", s, total[s])) end
    io.write(string.format("cache_hits %d\n", h))
    io.write(string.format("requests_per_s %.1f\n", summary.requests / (summary.duration / 1e6)))
    io.write(string.format("latency_p50_ms %.2f\nlatency_p99_ms %.2f\n",
        latency:percentile(50) / 1e3, latency:percentile(99) / 1e3))
    local e = summary.errors
    io.write(string.format("socket_errors %d\n", e.connect + e.read + e.write + e.timeout))
end

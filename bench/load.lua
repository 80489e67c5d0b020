-- load.lua -- wrk script of bench/load.sh: cycles through good and bad requests and tallies
-- the answers by status (wrk itself only counts "non-2xx or 3xx").
-- Good computations carry a per-request tol (1e-4 times 1 + a tiny counter term) so that
-- most miss the answer cache and take a compute slot; one good request repeats exactly and
-- is answered from the cache. The bad ones cover 400, 404, 405, 413-free paths, 415 and 422.
local psd = '"psd":{"kind":"power","D":2.5,"k1":1,"k2":8,"C":0.0796}'
local json = { ["Content-Type"] = "application/json" }
local n = 0

local function tol()
    n = n + 1
    return string.format('"tol":%.12g', 1e-4 * (1 + n * 1e-9 + math.random() * 1e-6))
end

local make = {
    function() return wrk.format("POST", "/v1/adhesion", json, "{" .. psd .. "}") end,
    function() return wrk.format("POST", "/v1/adhesion", json, "{" .. psd .. "," .. tol() .. "}") end,
    function()
        return wrk.format("POST", "/v1/traction", json,
            "{" .. psd .. "," .. tol() .. ',"g_ave":[2,2.5,3,4]}')
    end,
    function()
        return wrk.format("POST", "/v1/pdf", json, "{" .. psd .. "," .. tol() .. ',"g_ave":2.5,"k2":[8]}')
    end,
    function()
        return wrk.format("POST", "/v1/contact", json, "{" .. psd .. "," .. tol() ..
            ',"material":{"E_star":1e9,"dgamma":0.05,"epsilon":3e-10},"R":1e-6}')
    end,
    function() return wrk.format("POST", "/v1/adhesion", json, '{"psd":{"kind":"power","D":2.') end,
    function()
        return wrk.format("POST", "/v1/adhesion", json,
            '{"psd":{"kind":"power","D":2.5,"k1":0.3,"C":0.1},"tol":"x","extra":1e400}')
    end,
    function() return wrk.format("POST", "/v1/nope", json, "{" .. psd .. "}") end,
    function() return wrk.format("POST", "/v1/adhesion", { ["Content-Type"] = "text/plain" }, "{}") end,
    function() return wrk.format("GET", "/v1/adhesion") end,
    function() return wrk.format("POST", "/v1/adhesion", json, "\0\1\2\255junk") end,
    function() return wrk.format("GET", "/healthz") end,
}

local threads = {}
function setup(thread)
    table.insert(threads, thread)
end

function init(args)
    counts = {}
    i = 0
    math.randomseed(os.time() + #threads)
end

function request()
    i = i % #make + 1
    return make[i]()
end

function response(status, headers, body)
    counts[status] = (counts[status] or 0) + 1
end

function done(summary, latency, requests)
    local total, keys = {}, {}
    for _, t in ipairs(threads) do
        for s, c in pairs(t:get("counts")) do
            total[s] = (total[s] or 0) + c
        end
    end
    for s in pairs(total) do table.insert(keys, s) end
    table.sort(keys)
    for _, s in ipairs(keys) do io.write(string.format("status %d %d\n", s, total[s])) end
    io.write(string.format("requests %d\nseconds %.2f\nrequests_per_s %.1f\n", summary.requests,
        summary.duration / 1e6, summary.requests / (summary.duration / 1e6)))
    for _, p in ipairs({ 50, 90, 99, 99.9 }) do
        io.write(string.format("latency_p%s_ms %.2f\n", p, latency:percentile(p) / 1e3))
    end
    io.write(string.format("latency_max_ms %.2f\n", latency.max / 1e3))
    local e = summary.errors
    io.write(string.format("socket_errors connect %d read %d write %d timeout %d\n", e.connect,
        e.read, e.write, e.timeout))
end

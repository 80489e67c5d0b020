#!/usr/bin/env python3
"""lab_clients.py -- three clients of one ljgapd, as in a lab, for bench/load.sh.

  lab_clients.py SECONDS URL        (URL: http://127.0.0.1:PORT)

From three loopback addresses, for SECONDS seconds (keep-alive connections, every request
distinct so that none is a cache hit):
  batch        127.0.0.2  a script firing slow requests (tol 1e-9: ~0.1 s each on a quiet machine) on 5 connections at once
  interactive  127.0.0.3  one person: a fast request (~10 ms), then 0.2 s of thinking, again
  mixed        127.0.0.4  2 connections alternating slow and fast requests
Prints, per client, the requests, the answers by status and the latency p50/p99/max in ms.
Loopback only; bounded by SECONDS (plus the last requests' own time, at most 60 s).
"""
import http.client
import itertools
import sys
import threading
import time

counter = itertools.count(1)
lock = threading.Lock()


def slow_body():
    n = next(counter)
    return ('{"psd":{"kind":"power","D":2.5,"k1":1,"k2":8,"C":%.12g},"tol":1e-9}'
            % (0.07 + n * 1e-7))


def fast_body():
    n = next(counter)
    return '{"psd":{"kind":"power","D":2.5,"k1":1,"m0":%.12g}}' % (0.3 + n * 1e-7)


def worker(port, src, kinds, think, t_end, out):
    conn = None
    for kind in itertools.cycle(kinds):
        if time.monotonic() >= t_end:
            break
        body = slow_body() if kind == "slow" else fast_body()
        t0 = time.monotonic()
        try:
            if conn is None:
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60,
                                                  source_address=(src, 0))
            conn.request("POST", "/v1/adhesion", body, {"Content-Type": "application/json"})
            resp = conn.getresponse()
            resp.read()
            status = resp.status
            if resp.getheader("Connection", "").lower() == "close":
                conn.close()
                conn = None
        except (OSError, http.client.HTTPException):
            status = 0
            if conn is not None:
                conn.close()
            conn = None
        with lock:
            out.append((status, 1e3 * (time.monotonic() - t0)))
        if think:
            time.sleep(think)
    if conn is not None:
        conn.close()


def pct(xs, p):
    xs = sorted(xs)
    if not xs:
        return float("nan")
    k = min(len(xs) - 1, max(0, int(round(p / 100.0 * (len(xs) - 1)))))
    return xs[k]


def main():
    seconds, port = float(sys.argv[1]), int(sys.argv[2].rstrip("/").rsplit(":", 1)[1])
    t_end = time.monotonic() + seconds
    clients = [
        ("batch", "127.0.0.2", [(["slow"], 0.0)] * 5),
        ("interactive", "127.0.0.3", [(["fast"], 0.2)]),
        ("mixed", "127.0.0.4", [(["slow", "fast"], 0.0)] * 2),
    ]
    results, threads = {}, []
    for name, src, conns in clients:
        results[name] = []
        for kinds, think in conns:
            t = threading.Thread(target=worker,
                                 args=(port, src, kinds, think, t_end, results[name]))
            t.start()
            threads.append(t)
    for t in threads:
        t.join()
    for name, src, _ in clients:
        r = results[name]
        lat = [ms for _, ms in r]
        statuses = {}
        for s, _ in r:
            statuses[s] = statuses.get(s, 0) + 1
        print("client %s %s requests %d statuses %s p50_ms %.1f p99_ms %.1f max_ms %.1f"
              % (name, src, len(r), ",".join("%d:%d" % kv for kv in sorted(statuses.items())),
                 pct(lat, 50), pct(lat, 99), max(lat) if lat else float("nan")))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""upload_clients.py -- many height-map uploads at once to POST /v1/psd, as curl sends them.

  upload_clients.py URL FILE N ADDRESSES [SECONDS]

N uploads of FILE (text/plain) at once, spread round-robin over ADDRESSES source addresses
127.0.0.1 .. 127.0.0.ADDRESSES, each on its own connection, each sending Expect: 100-continue
as curl does for a large body: the body goes out once the server says 100 Continue, and a server
that answers at once (503, 413) is heard without the body being sent. Prints one line per
status, "STATUS COUNT retry_after=COUNT_WITH_RETRY_AFTER", and "seconds S". Standard library
only.
"""
import socket
import sys
import threading
import time
from collections import Counter
from urllib.parse import urlparse


def read_head(sock, buf):
    while b"\r\n\r\n" not in buf:
        d = sock.recv(65536)
        if not d:
            raise ConnectionError("closed before the answer")
        buf += d
    head, rest = buf.split(b"\r\n\r\n", 1)
    lines = head.decode("latin1").split("\r\n")
    status = int(lines[0].split()[1])
    hdrs = {}
    for l in lines[1:]:
        k, _, v = l.partition(":")
        hdrs[k.strip().lower()] = v.strip()
    return status, hdrs, rest


def read_body(sock, hdrs, rest):
    n = int(hdrs.get("content-length", "0"))
    while len(rest) < n:
        d = sock.recv(65536)
        if not d:
            break
        rest += d
    return rest[:n]


def upload(u, data, source, timeout, out, lock):
    s = socket.create_connection((u.hostname, u.port), timeout=timeout, source_address=(source, 0))
    try:
        head = (f"POST {u.path or '/'}{'?' + u.query if u.query else ''} HTTP/1.1\r\nHost: {u.netloc}\r\n"
                f"Content-Type: text/plain\r\nContent-Length: {len(data)}\r\nExpect: 100-continue\r\n\r\n")
        s.sendall(head.encode())
        status, hdrs, rest = read_head(s, b"")
        if status == 100:
            s.sendall(data)
            status, hdrs, rest = read_head(s, rest)
        read_body(s, hdrs, rest)
        res = (status, "retry-after" in hdrs)
    except Exception as e:  # a reset or a timeout counts as status 0
        res = (0, False)
    finally:
        s.close()
    with lock:
        out.append(res)


def main():
    url, path, n, naddr = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    timeout = float(sys.argv[5]) if len(sys.argv) > 5 else 300
    u = urlparse(url)
    data = open(path, "rb").read()
    out, lock = [], threading.Lock()
    t0 = time.time()
    th = [threading.Thread(target=upload, args=(u, data, f"127.0.0.{1 + i % naddr}", timeout, out, lock))
          for i in range(n)]
    for t in th:
        t.start()
    for t in th:
        t.join()
    c = Counter(s for s, _ in out)
    ra = Counter(s for s, r in out if r)
    for s in sorted(c):
        print(f"{s} {c[s]} retry_after={ra[s]}")
    print(f"seconds {time.time() - t0:.1f}")


if __name__ == "__main__":
    main()

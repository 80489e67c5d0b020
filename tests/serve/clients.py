#!/usr/bin/env python3
"""clients.py -- misbehaving clients for tests/serve/run.sh (loopback only, bounded in time).

  clients.py hold PORT SRC IDLE DRIP SECONDS
      Opens IDLE connections that send nothing and DRIP connections that send a request's
      headers one byte every 2 s, all from source address SRC to 127.0.0.1:PORT. After 1 s it
      prints "open N closed M" (connections still open / closed by the server), then keeps the
      open ones (dripping) until SECONDS have passed or it is killed.
  clients.py probe PORT SRC N
      Opens N connections from SRC one after the other and prints how many the server kept
      open and how many it closed at once ("kept K refused R").
  clients.py drip PORT SRC INTERVAL LIMIT
      One connection sending "GET /healthz HTTP/1.1..." one byte every INTERVAL seconds;
      prints the seconds until the server closed it, or "open" after LIMIT seconds.
  clients.py half PORT BODY
      Sends a POST /v1/adhesion with BODY, shuts down its sending side at once, reads the
      answer until the server closes (within 30 s) and prints its status code and the problem
      type of its body ("503 /problems/unavailable"), or "none".
Every socket is closed on exit; every loop is bounded by its arguments.
"""
import re
import select
import socket
import sys
import time

REQ = b"GET /healthz HTTP/1.1\r\nHost: x\r\nUser-Agent: drip\r\n\r\n"


def connect(port, src):
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.bind((src, 0))
    s.settimeout(5)
    s.connect(("127.0.0.1", port))
    s.setblocking(False)
    return s


def closed_by_peer(s, wait=0.0):
    """True when the server closed s (end of stream or reset) within wait seconds."""
    r, _, _ = select.select([s], [], [], wait)
    if not r:
        return False
    try:
        return s.recv(4096) == b""
    except (ConnectionResetError, BrokenPipeError):
        return True
    except BlockingIOError:
        return False


def hold(port, src, idle, drip, seconds):
    socks, drips, failed = [], [], 0
    for i in range(idle + drip):
        try:
            s = connect(port, src)
        except OSError:
            failed += 1
            continue
        (drips if i >= idle else socks).append([s, 0])
    time.sleep(1.0)
    alive = [c for c in socks + drips if not closed_by_peer(c[0])]
    print("open %d closed %d" % (len(alive), idle + drip - len(alive)), flush=True)
    t_end = time.monotonic() + seconds
    last = 0.0
    while time.monotonic() < t_end:
        if time.monotonic() - last >= 2.0:
            last = time.monotonic()
            for c in drips:
                if c[1] < len(REQ) - 4:  # never complete the request
                    try:
                        c[0].send(REQ[c[1]:c[1] + 1])
                        c[1] += 1
                    except OSError:
                        pass
        time.sleep(0.2)
    for c in socks + drips:
        c[0].close()


def probe(port, src, n):
    socks, refused = [], 0
    for _ in range(n):
        try:
            s = connect(port, src)
        except OSError:
            refused += 1
            continue
        if closed_by_peer(s, 0.3):
            refused += 1
            s.close()
        else:
            socks.append(s)
    kept = sum(1 for s in socks if not closed_by_peer(s, 0.0))
    print("kept %d refused %d" % (kept, n - kept), flush=True)
    for s in socks:
        s.close()


def drip(port, src, interval, limit):
    s = connect(port, src)
    t0 = time.monotonic()
    i = 0
    while time.monotonic() - t0 < limit:
        if closed_by_peer(s, interval):
            print("%.2f" % (time.monotonic() - t0), flush=True)
            s.close()
            return
        try:
            s.send(REQ[i % (len(REQ) - 4):i % (len(REQ) - 4) + 1])
        except OSError:
            print("%.2f" % (time.monotonic() - t0), flush=True)
            s.close()
            return
        i += 1
    print("open", flush=True)
    s.close()


def half(port, body):
    s = socket.create_connection(("127.0.0.1", port), timeout=30)
    data = body.encode()
    s.sendall(b"POST /v1/adhesion HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
              b"Content-Length: %d\r\n\r\n" % len(data) + data)
    s.shutdown(socket.SHUT_WR)
    answer = b""
    try:
        while len(answer) < 1 << 20:
            d = s.recv(65536)
            if not d:
                break
            answer += d
    except OSError:
        pass
    s.close()
    m = re.match(rb"HTTP/1\.[01] (\d{3})", answer)
    t = re.search(rb'"type":"([^"]*)"', answer)
    print("%s %s" % (m.group(1).decode(), t.group(1).decode() if t else "-") if m else "none",
          flush=True)


def main(argv):
    cmd, port = argv[1], int(argv[2])
    if cmd == "hold":
        hold(port, argv[3], int(argv[4]), int(argv[5]), float(argv[6]))
    elif cmd == "probe":
        probe(port, argv[3], int(argv[4]))
    elif cmd == "drip":
        drip(port, argv[3], float(argv[4]), float(argv[5]))
    elif cmd == "half":
        half(port, argv[3])
    else:
        sys.exit("usage: see the file's docstring")


if __name__ == "__main__":
    main(sys.argv)

"""Hostile HTTP against the view server of a running `radiosity --view`
(tests/view.sh), on loopback only: malformed and oversized requests, a
client that connects and says nothing, one that stops half way through its
request, and 200 connections at once. Each must get an error status (or
the connection closed by the server in its own time), never a stall; one
line per check (ok: ... / FAIL: ...), as tests/lib.sh prints them.

usage: http_abuse.py PORT
"""

import socket
import sys
import threading
import time

HOST = "127.0.0.1"
# The server's kIdleTimeout and kReadTimeout (viewserver.h) are 2 s: a
# silent or stalled client must be let go well within this.
LET_GO = 8
FAILS = 0


def report(good, what):
    global FAILS
    if not good:
        FAILS += 1
    print(("ok: " if good else "FAIL: ") + what, flush=True)


def exchange(port, data, timeout=10):
    """Sends data, reads until the server closes or the status line and
    headers are in; returns (status or None, seconds)."""
    t0 = time.monotonic()
    s = socket.create_connection((HOST, port), timeout=timeout)
    try:
        try:
            s.sendall(data)
        except (BrokenPipeError, ConnectionResetError):
            pass  # refused part way: the answer may be in already
        got = b""
        while b"\r\n\r\n" not in got:
            try:
                chunk = s.recv(65536)
            except ConnectionResetError:
                break
            if not chunk:
                break
            got += chunk
    except socket.timeout:
        return None, time.monotonic() - t0
    finally:
        s.close()
    status = None
    if got.startswith(b"HTTP/1.1 ") and len(got) >= 12 and got[9:12].isdigit():
        status = int(got[9:12])
    return status, time.monotonic() - t0


def request(path, method="GET", headers="Host: 127.0.0.1\r\n", body=b""):
    return (method.encode() + b" " + path.encode() + b" HTTP/1.1\r\n" + headers.encode() +
            b"Connection: close\r\n\r\n" + body)


def watch(s, name, opened, out):
    """Waits for the server to let the client go; out[name] = seconds."""
    s.settimeout(LET_GO)
    try:
        s.recv(65536)  # an answer (408, 400) or the end of the connection
        out[name] = time.monotonic() - opened
    except ConnectionResetError:
        out[name] = time.monotonic() - opened
    except socket.timeout:
        out[name] = None
    finally:
        s.close()


def main():
    port = int(sys.argv[1])
    # Held open through the rest: the server must go on serving meanwhile.
    let_go = {}
    watchers = []
    for name, data in (("a silent client", b""),
                       ("a client stalled inside its request", b"GET /state.json HTTP/1.1\r\nHost: 127.0")):
        s = socket.create_connection((HOST, port))
        if data:
            s.sendall(data)
        watchers.append(threading.Thread(target=watch, args=(s, name, time.monotonic(), let_go)))
        watchers[-1].start()

    bad = [
        ("a 100 kB URL", request("/" + "a" * 100000), (414, 400)),
        ("a 100 kB header", request("/", headers="Host: 127.0.0.1\r\nX-Long: " + "b" * 100000 + "\r\n"), (400, 431)),
        ("an unknown method", request("/", method="BREW"), (400, 405, 501)),
        ("POST with a body", request("/state.json", method="POST", headers="Host: 127.0.0.1\r\nContent-Length: 5\r\n", body=b"hello"), (404, 405)),
        ("a 1 GB Content-Length", request("/", method="POST", headers="Host: 127.0.0.1\r\nContent-Length: 1000000000\r\n"), (413, 400)),
        ("binary garbage", bytes(range(256)) * 4 + b"\r\n\r\n", (400,)),
        ("no HTTP version", b"GET /\r\n\r\n", (400,)),
        ("a path out of the tree", request("/../../../etc/passwd"), (400, 404)),
        ("an unknown path", request("/result.csv"), (404,)),
        ("rows=-5", request("/state.json?rows=-5"), (400,)),
        ("rows=x", request("/state.json?rows=x"), (400,)),
        ("a foreign Host (DNS rebinding)", request("/state.json", headers="Host: evil.example:80\r\n"), (403,)),
    ]
    # All at once (some are answered only after the server's read timeout).
    answers = [None] * len(bad)

    def ask(i):
        answers[i] = exchange(port, bad[i][1])

    threads = [threading.Thread(target=ask, args=(i,)) for i in range(len(bad))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for (what, _, want), (status, secs) in zip(bad, answers):
        report(status in want, "%s: status %s in %.2f s (want %s)" % (what, status, secs, " or ".join(map(str, want))))

    # Still served, the silent and stalled clients notwithstanding.
    status, secs = exchange(port, request("/state.json?rows=1000000000"))
    report(status == 200, "state.json with a silent and a stalled client connected: status %s in %.2f s" % (status, secs))

    # 200 clients at once, each connecting and asking as soon as it may.
    n = 200
    results = [None] * n
    go = threading.Barrier(n)

    def one(i):
        go.wait()
        try:
            with socket.create_connection((HOST, port), timeout=20) as s:
                s.sendall(request("/state.json?rows=1000000000"))
                got = b""
                while True:
                    chunk = s.recv(65536)
                    if not chunk:
                        break
                    got += chunk
            results[i] = int(got[9:12]) if got.startswith(b"HTTP/1.1 ") else "no status"
        except OSError as e:
            results[i] = str(e)

    t0 = time.monotonic()
    threads = [threading.Thread(target=one, args=(i,)) for i in range(n)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    answered = sum(1 for r in results if r == 200)
    others = sorted(set(str(r) for r in results if r != 200))
    report(answered == n, "%d connections at once: %d answered 200 in %.2f s%s" %
           (n, answered, time.monotonic() - t0, (" (others: " + ", ".join(others) + ")") if others else ""))

    for t in watchers:
        t.join()
    for name, secs in let_go.items():
        report(secs is not None, "%s: let go by the server after %s (want within %d s)" %
               (name, "%.1f s" % secs if secs is not None else "never", LET_GO))
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""N sequential SDO reads through one front end, one at a time, on one
connection (bench/sdo_latency.sh). Prints one line:
  LABEL  n=N  mean=M ms  p50=.. p90=.. p99=.. max=..
and exits 1 when any answer is not a value.

  sdo_latency_client.py rest LABEL HOST PORT PATH N
  sdo_latency_client.py ascii LABEL HOST PORT "REQUEST" N
REQUEST is a CiA 309-3 request without its sequence, e.g. "5 read 0x1017 0 u16";
each is sent as "[k] REQUEST" and its answer line "[k] VALUE" awaited.
"""
import socket
import statistics
import sys
import time


def report(label, times):
    ms = sorted(t * 1000.0 for t in times)
    pick = lambda q: ms[min(len(ms) - 1, int(q * len(ms)))]
    print("%-34s n=%d  mean=%.3f ms  p50=%.3f  p90=%.3f  p99=%.3f  max=%.3f" %
          (label, len(ms), statistics.fmean(ms), pick(0.5), pick(0.9), pick(0.99), ms[-1]), flush=True)


def receive_until(s, buf, label, enough):
    """Reads from s onto buf until enough(buf); exits when the peer closes."""
    while not enough(buf):
        chunk = s.recv(65536)
        if not chunk:
            sys.exit("%s: connection closed" % label)
        buf += chunk
    return buf


def rest(label, host, port, path, n):
    # A raw HTTP/1.1 keep-alive client, as lean as the ASCII one below
    # (http.client costs the client ~0.3 ms a request under UML).
    s = socket.create_connection((host, int(port)))
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    request = ("GET %s HTTP/1.1\r\nHost: %s\r\n\r\n" % (path, host)).encode()
    buf = b""
    times = []
    for _ in range(10 + n):  # 10 to warm up (connection, caches)
        t0 = time.perf_counter()
        s.sendall(request)
        buf = receive_until(s, buf, label, lambda b: b"\r\n\r\n" in b)
        head, buf = buf.split(b"\r\n\r\n", 1)
        length = 0
        for line in head.split(b"\r\n")[1:]:
            k, _, v = line.partition(b":")
            if k.strip().lower() == b"content-length":
                length = int(v)
        buf = receive_until(s, buf, label, lambda b: len(b) >= length)
        body, buf = buf[:length], buf[length:]
        t1 = time.perf_counter()
        status = head.split(b" ", 2)[1]
        if status != b"200":
            sys.exit("%s: HTTP %s %s" % (label, status.decode(), body[:200]))
        times.append(t1 - t0)
    report(label, times[10:])


def ascii(label, host, port, request, n):
    if host.startswith("unix:"):
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.connect(host[5:])
    else:
        s = socket.create_connection((host, int(port)))
        s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    buf = b""
    times = []
    for k in range(1, 11 + n):
        t0 = time.perf_counter()
        s.sendall(b"[%d] %s\r\n" % (k, request.encode()))
        buf = receive_until(s, buf, label, lambda b: b"\n" in b)
        line, buf = buf.split(b"\n", 1)
        t1 = time.perf_counter()
        text = line.decode(errors="replace").strip()
        if not text.startswith("[%d]" % k) or "ERROR" in text:
            sys.exit("%s: answer %r" % (label, text))
        times.append(t1 - t0)
    report(label, times[10:])


if __name__ == "__main__":
    mode, label = sys.argv[1], sys.argv[2]
    if mode == "rest":
        rest(label, sys.argv[3], sys.argv[4], sys.argv[5], int(sys.argv[6]))
    elif mode == "ascii":
        ascii(label, sys.argv[3], sys.argv[4], sys.argv[5], int(sys.argv[6]))
    else:
        sys.exit(__doc__)

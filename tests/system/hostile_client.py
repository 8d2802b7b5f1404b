#!/usr/bin/env python3
"""What a hostile web page, a request smuggler and a connection hog try against
the gateway (issue 12), for the system test; standard library only. Raw
requests over TLS so Host, Origin and framing are exactly as written.
Prints one line per check; exits 1 at the first failure.

usage: hostile_client.py PORT CA_FILE PER_ADDRESS_CAP
       (tokens: env VIEWER, OPERATOR; the gateway listens on 127.0.0.1:PORT
       with nodes 5 and 10 operational)
"""
import json
import os
import socket
import ssl
import sys
import time

PORT, CA, CAP = int(sys.argv[1]), sys.argv[2], int(sys.argv[3])
VIEWER, OPERATOR = os.environ["VIEWER"], os.environ["OPERATOR"]
CTX = ssl.create_default_context(cafile=CA)
OWN = f"127.0.0.1:{PORT}"
N10 = "/api/v1/networks/1/nodes/10"


def check(cond, what, detail=""):
    if not cond:
        print(f"FAIL: {what} {detail}")
        sys.exit(1)
    print(f"ok: {what}")


def exchange(data, source=None, timeout=10):
    """Sends raw bytes over TLS; returns everything until the server closes."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.settimeout(timeout)
    if source:
        sock.bind((source, 0))
    sock.connect(("127.0.0.1", PORT))
    tls = CTX.wrap_socket(sock, server_hostname="127.0.0.1")
    tls.sendall(data)
    out = b""
    try:
        while True:
            chunk = tls.recv(65536)
            if not chunk:
                break
            out += chunk
    except (ConnectionResetError, ssl.SSLError, socket.timeout):
        pass
    tls.close()
    return out


def request(method, path, headers, body=b"", source=None):
    head = f"{method} {path} HTTP/1.1\r\n"
    if not any(h.lower().startswith("host:") for h in headers):
        head += f"Host: {OWN}\r\n"
    head += "".join(h + "\r\n" for h in headers)
    if body and not any(h.lower().startswith(("content-length:", "transfer-encoding:")) for h in headers):
        head += f"Content-Length: {len(body)}\r\n"
    out = exchange((head + "Connection: close\r\n\r\n").encode() + body, source)
    status = int(out.split(b" ", 2)[1]) if out.startswith(b"HTTP/1.1 ") else 0
    return status, out


def expect(want, what, method, path, headers, body=b"", source=None):
    status, out = request(method, path, headers, body, source)
    check(status == want, f"{what} -> {want}", f"got {status}: {out[:300]!r}")
    return out


def node10_state():
    out = expect(200, "read node 10", "GET", N10, [f"Authorization: Bearer {VIEWER}"])
    return json.loads(out.split(b"\r\n\r\n", 1)[1]).get("state")


stop = b'{"command": "stop"}'
op = f"Authorization: Bearer {OPERATOR}"

# CSRF: a page on another site posts "stop" as text/plain (no preflight), even
# with the operator's token (e.g. a proxy that adds it).
expect(403, "cross-site text/plain NMT stop with a token", "POST", N10 + "/nmt",
       [op, "Content-Type: text/plain;charset=UTF-8", "Origin: https://evil.example"], stop)
expect(403, "cross-site JSON NMT stop", "POST", N10 + "/nmt",
       [op, "Content-Type: application/json", "Origin: https://evil.example"], stop)
expect(415, "text/plain NMT stop without Origin (old browsers)", "POST", N10 + "/nmt",
       [op, "Content-Type: text/plain"], stop)
# DNS rebinding: the attacker's name resolves to the gateway; the browser sends it as Host.
expect(421, "SDO read with a rebinding Host", "GET", N10 + "/sdo/1018/1",
       [f"Host: rebind.attacker.example:{PORT}", f"Authorization: Bearer {VIEWER}"])
expect(421, "dashboard with a rebinding Host", "GET", "/", [f"Host: rebind.attacker.example:{PORT}"])
check(node10_state() == "operational", "node 10 still operational after the refused stops")
# The dashboard's own request (same origin) and scripts (no Origin) work.
expect(200, "same-origin SYNC", "POST", "/api/v1/networks/1/sync",
       [op, "Content-Type: application/json", f"Origin: https://{OWN}"], b"{}")
expect(200, "SYNC from a script", "POST", "/api/v1/networks/1/sync", [op, "Content-Type: application/json"], b"{}")
# Cross-site WebSocket hijacking: the token in the query does not help.
key = "dGhlIHNhbXBsZSBub25jZQ=="
expect(403, "event stream upgrade from another origin", "GET", f"/api/v1/events?access_token={VIEWER}",
       ["Upgrade: websocket", "Connection: Upgrade", f"Sec-WebSocket-Key: {key}", "Sec-WebSocket-Version: 13",
        "Origin: https://evil.example"])

# Request smuggling: each is refused and the request hidden behind it never runs.
smuggled = f"GET /api/v1/gateway HTTP/1.1\r\nHost: {OWN}\r\nAuthorization: Bearer {VIEWER}\r\n\r\n".encode()
for label, fields in (("Transfer-Encoding: xchunked", ["Transfer-Encoding: xchunked"]),
                      ("Transfer-Encoding: chunked, identity", ["Transfer-Encoding: chunked, identity"]),
                      ("Transfer-Encoding and Content-Length", ["Transfer-Encoding: chunked", "Content-Length: 5"]),
                      ("two Content-Length values", ["Content-Length: 5", "Content-Length: 7"]),
                      ("two Authorization fields", [f"Authorization: Bearer {VIEWER}"])):
    out = expect(400, f"SYNC with {label}", "POST", "/api/v1/networks/1/sync",
                 [op, "Content-Type: application/json"] + fields, b"0\r\n\r\n" + smuggled)
    check(out.count(b"HTTP/1.1 ") == 1, "  nothing answered after it", out[:400])

# One client address holding its whole share idle (a slowloris client, or
# every client behind one reverse proxy): it is not locked out, its longest
# idle connections make room for its new ones (contract "REST and
# WebSocket"; issue 27 item 10), and another address is served meanwhile.
held = []
for _ in range(CAP):
    s = socket.create_connection(("127.0.0.1", PORT), timeout=5)
    held.append(s)
time.sleep(0.5)
for i in range(3):  # each new one closes the longest idle one, and stays
    held.append(socket.create_connection(("127.0.0.1", PORT), timeout=5))
    time.sleep(0.2)


def closed_by_server(s):
    s.settimeout(0.5)
    try:
        return s.recv(1) == b""
    except ConnectionResetError:
        return True
    except socket.timeout:
        return False


for i in range(3):
    check(closed_by_server(held[i]), f"held connection {i + 1} (the longest idle) closed for a new one")
check(not closed_by_server(held[3]), "the next held connection still open")
expect(200, f"a request from 127.0.0.1 at its cap of {CAP} idle connections", "GET", "/api/v1/gateway",
       [f"Authorization: Bearer {VIEWER}"])
expect(200, "127.0.0.2 served meanwhile", "GET", "/api/v1/gateway", [f"Authorization: Bearer {VIEWER}"],
       source="127.0.0.2")
for s in held:
    s.close()
time.sleep(0.5)
metrics = expect(200, "metrics", "GET", "/metrics", [f"Authorization: Bearer {VIEWER}"]).decode()
for line in ('canopen_gateway_http_connections_refused_total{reason="per-address"} 0',
             'canopen_gateway_http_connections_evicted_total 4',
             'canopen_gateway_http_requests_refused_total{reason="origin"} 3',
             'canopen_gateway_http_requests_refused_total{reason="host"} 2',
             'canopen_gateway_http_requests_refused_total{reason="media-type"} 1'):
    check(line + "\n" in metrics, f"/metrics: {line}")
print("hostile checks done")

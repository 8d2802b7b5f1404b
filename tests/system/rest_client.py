#!/usr/bin/env python3
"""REST API checks for the system test (standard library only): every route
of ../shared/api-contract.md over HTTPS with bearer tokens against a gateway
on vcan0 whose nodes 5 (CiA 402) and 10 (CiA 401) are canopen-sim devices.
Prints one line per check; exits 1 at the first failure.

usage: rest_client.py BASE_URL CA_FILE   (tokens: env VIEWER, OPERATOR, ADMIN)
"""
import json
import os
import ssl
import sys
import threading
import time
import urllib.error
import urllib.request

BASE, CA = sys.argv[1], sys.argv[2]
TOKENS = {"viewer": os.environ["VIEWER"], "operator": os.environ["OPERATOR"], "admin": os.environ["ADMIN"]}
CTX = ssl.create_default_context(cafile=CA)


def call(method, path, body=None, role=None, timeout=15):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(BASE + path, data=data, method=method)
    if data is not None:
        req.add_header("Content-Type", "application/json")
    if role:
        req.add_header("Authorization", "Bearer " + TOKENS[role])
    try:
        with urllib.request.urlopen(req, context=CTX, timeout=timeout) as r:
            raw, status, ctype = r.read(), r.status, r.headers.get("Content-Type", "")
    except urllib.error.HTTPError as e:
        raw, status, ctype = e.read(), e.code, e.headers.get("Content-Type", "")
    try:
        doc = json.loads(raw) if ctype.startswith("application/") and "json" in ctype else raw.decode()
    except ValueError:
        doc = raw.decode(errors="replace")
    return status, doc


def check(cond, what, detail=""):
    if not cond:
        print(f"FAIL: {what} {detail}")
        sys.exit(1)
    print(f"ok: {what}")


def expect(status_want, method, path, body=None, role=None):
    status, doc = call(method, path, body, role)
    check(status == status_want, f"{method} {path} as {role or 'nobody'} -> {status_want}", f"got {status}: {doc}")
    return doc


N5, N10 = "/api/v1/networks/1/nodes/5", "/api/v1/networks/1/nodes/10"

# Nothing without a token; a viewer reads, but does not write.
expect(401, "GET", "/api/v1/gateway")
gw = expect(200, "GET", "/api/v1/gateway", role="viewer")
check(gw["networks"][0]["interface"] == "vcan0", "gateway lists vcan0", gw)
net = expect(200, "GET", "/api/v1/networks/1", role="viewer")
check(net["bus"] == "error-active", "bus state error-active", net)
expect(404, "GET", "/api/v1/networks/9", role="viewer")

nodes = expect(200, "GET", "/api/v1/networks/1/nodes", role="viewer")
ids = sorted(n["node"] for n in nodes["nodes"])
check(5 in ids and 10 in ids, "nodes 5 and 10 known", ids)
one = expect(200, "GET", N5, role="viewer")
check(one.get("state") == "operational", "node 5 operational", one)
check(any(v.get("name") == "Statusword" for v in one.get("values", [])), "node 5's latest TPDO values by name", one)

od = expect(200, "GET", N5 + "/od", role="viewer")
check(any(o.get("index") == 0x1017 for o in od.get("objects", [])), "OD from the EDS has 1017h", str(od)[:200])
expect(200, "GET", N5 + "/emcy", role="viewer")

# SDO: typed from the EDS, round trip, and each error of the contract.
dt = expect(200, "GET", N10 + "/sdo/1000/0", role="viewer")
check(dt["type"] == "u32" and isinstance(dt["value"], int), "SDO read typed from the EDS", dt)
expect(403, "PUT", N10 + "/sdo/1017/0", {"value": 250}, role="viewer")
expect(200, "PUT", N10 + "/sdo/1017/0", {"value": 250}, role="operator")
hb = expect(200, "GET", N10 + "/sdo/0x1017/0", role="viewer")
check(hb["value"] == 250 and hb["type"] == "u16", "SDO write/read round trip", hb)
ro = expect(422, "PUT", N10 + "/sdo/1000/0", {"value": 1}, role="operator")
check(ro.get("abortCode") == "0x06010002", "SDO abort code of a read-only object", ro)
expect(400, "PUT", N5 + "/sdo/6060/0", {"value": 300}, role="operator")  # i8
expect(400, "PUT", N5 + "/sdo/6060/0", {"value": "x"}, role="operator")
expect(404, "GET", N5 + "/sdo/5fff/0", role="viewer")
expect(504, "GET", "/api/v1/networks/1/nodes/99/sdo/1000/0?type=u32", role="viewer")

# RPDO, SYNC, NMT with their roles; resets need admin.
expect(200, "PUT", N5 + "/rpdo/1", {"values": [{"index": "0x6040", "subIndex": 0, "value": 15}]}, role="operator")
expect(400, "PUT", N5 + "/rpdo/1", {"raw": "00"}, role="operator")
expect(200, "POST", "/api/v1/networks/1/sync", {}, role="operator")
expect(403, "POST", N10 + "/nmt", {"command": "reset-node"}, role="operator")
expect(200, "POST", N10 + "/nmt", {"command": "stop"}, role="operator")
deadline = time.time() + 10
while time.time() < deadline and call("GET", N10, role="viewer")[1].get("state") != "stopped":
    time.sleep(0.2)
check(call("GET", N10, role="viewer")[1].get("state") == "stopped", "node 10 stopped after NMT stop")
expect(200, "POST", N10 + "/nmt", {"command": "reset-node"}, role="admin")
deadline = time.time() + 15
while time.time() < deadline and call("GET", N10, role="viewer")[1].get("state") != "operational":
    time.sleep(0.2)
check(call("GET", N10, role="viewer")[1].get("state") == "operational", "node 10 booted and started again after reset")

metrics = expect(200, "GET", "/metrics", role="viewer")
check("canopen_gateway_sdo_requests_total" in metrics, "/metrics has SDO counters")
status, _ = call("GET", "/api/v1/openapi.json")
check(status == 200, "OpenAPI document is public", status)

# 429: more requests for one node than its SDO queue holds (32 behind the
# running one); node 98 is silent, so they pile up.
results = []


def one_read():
    results.append(call("GET", "/api/v1/networks/1/nodes/98/sdo/1000/0?type=u32", role="viewer", timeout=60)[0])


threads = [threading.Thread(target=one_read, daemon=True) for _ in range(45)]
for t in threads:
    t.start()
deadline = time.time() + 20
while time.time() < deadline and 429 not in results:
    time.sleep(0.1)
check(429 in results, "429 when the node's SDO queue is full", sorted(set(results)))
print("rest checks done")

#!/usr/bin/env python3
"""One REST call for the maintenance system tests (standard library only).

usage: maint_call.py METHOD URL [BODY_FILE [CONTENT_TYPE]]
Prints "STATUS" on the first line, then the response headers as
"name: value" lines, an empty line, and the body (problems too). Loopback
without tokens acts as admin. Waits up to 200 s: a program download answers
when it is done.
"""
import sys
import urllib.error
import urllib.request

method, url = sys.argv[1], sys.argv[2]
data = open(sys.argv[3], "rb").read() if len(sys.argv) > 3 else None
req = urllib.request.Request(url, data=data, method=method)
if data is not None:
    req.add_header("Content-Type", sys.argv[4] if len(sys.argv) > 4 else "application/octet-stream")
try:
    r = urllib.request.urlopen(req, timeout=200)
    status, headers, body = r.status, r.headers, r.read()
except urllib.error.HTTPError as e:
    status, headers, body = e.code, e.headers, e.read()
print(status)
for k, v in headers.items():
    print(f"{k.lower()}: {v}")
print()
sys.stdout.write(body.decode("utf-8", errors="replace"))

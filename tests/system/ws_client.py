#!/usr/bin/env python3
"""Minimal WebSocket client for the system tests (RFC 6455, standard library
only): connects to ws://HOST:PORT/api/v1/events, sends the subscription
filter as a text message, prints COUNT event messages (one JSON per line) and
exits 0; exits 1 on a handshake failure or when nothing comes for 15 s.

usage: ws_client.py HOST PORT FILTER_JSON COUNT [PATH]
With WS_CA=<PEM file> in the environment it speaks TLS (wss://), checking
the server's certificate against that CA.
"""
import base64
import os
import socket
import ssl
import struct
import sys


def send_frame(sock, opcode, payload):
    mask = os.urandom(4)
    header = bytes([0x80 | opcode])
    n = len(payload)
    if n < 126:
        header += bytes([0x80 | n])
    elif n < 65536:
        header += bytes([0x80 | 126]) + struct.pack("!H", n)
    else:
        header += bytes([0x80 | 127]) + struct.pack("!Q", n)
    masked = bytes(b ^ mask[i % 4] for i, b in enumerate(payload))
    sock.sendall(header + mask + masked)


def recv_exact(sock, n):
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            raise ConnectionError("connection closed")
        data += chunk
    return data


def recv_frame(sock):
    b0, b1 = recv_exact(sock, 2)
    n = b1 & 0x7F
    if n == 126:
        n = struct.unpack("!H", recv_exact(sock, 2))[0]
    elif n == 127:
        n = struct.unpack("!Q", recv_exact(sock, 8))[0]
    if b1 & 0x80:
        recv_exact(sock, 4)  # servers do not mask; tolerate it anyway
    return b0 & 0x0F, recv_exact(sock, n)


def main():
    host, port, filt, count = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
    path = sys.argv[5] if len(sys.argv) > 5 else "/api/v1/events"
    sock = socket.create_connection((host, port), timeout=15)
    if os.environ.get("WS_CA"):
        ctx = ssl.create_default_context(cafile=os.environ["WS_CA"])
        sock = ctx.wrap_socket(sock, server_hostname=host)
    key = base64.b64encode(os.urandom(16)).decode()
    sock.sendall((f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
                  f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
    head = b""
    while b"\r\n\r\n" not in head:
        head += recv_exact(sock, 1)
    status = head.split(b"\r\n")[0].decode()
    if " 101 " not in status:
        print("# handshake failed:", status)
        return 1
    send_frame(sock, 0x1, filt.encode())
    got = 0
    subscribed = False  # events before the server confirms the filter are unfiltered
    while got < count:
        opcode, payload = recv_frame(sock)
        if opcode == 0x9:  # ping
            send_frame(sock, 0xA, payload)
        elif opcode == 0x8:
            print("# closed by server:", payload[2:].decode(errors="replace"))
            return 1
        elif opcode in (0x1, 0x2):
            text = payload.decode(errors="replace")
            if text.startswith('{"subscribed"') or text.startswith('{"error"'):  # control, not an event
                print("#", text)
                subscribed = subscribed or text.startswith('{"subscribed"')
                continue
            if not subscribed:
                continue
            print(text)
            got += 1
    send_frame(sock, 0x8, struct.pack("!H", 1000))
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except (OSError, ConnectionError) as e:
        print("# error:", e)
        sys.exit(1)

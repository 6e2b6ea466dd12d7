#!/usr/bin/env python3
"""Minimal WebSocket client (RFC 6455) for the integration test: connects to /v1/stream, prints
each text message as one line to stdout until the connection closes or the timeout passes."""
import base64, os, socket, sys, time

host, port, token, seconds = sys.argv[1], int(sys.argv[2]), sys.argv[3], float(sys.argv[4])
path = sys.argv[5] if len(sys.argv) > 5 else "/v1/stream"
s = socket.create_connection((host, port))
key = base64.b64encode(os.urandom(16)).decode()
s.sendall((f"GET {path} HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
           f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\nAuthorization: Bearer {token}\r\n\r\n").encode())
head = b""
while b"\r\n\r\n" not in head:
    chunk = s.recv(1)
    if not chunk:
        sys.exit("connection closed during handshake")
    head += chunk
status = head.split(b"\r\n")[0].decode()
print("STATUS " + status, flush=True)
if " 101 " not in status:
    sys.exit(0)
deadline = time.time() + seconds
buf = b""

def need(n):
    global buf
    while len(buf) < n:
        s.settimeout(max(0.01, deadline - time.time()))
        chunk = s.recv(65536)
        if not chunk:
            raise EOFError
        buf += chunk

try:
    while time.time() < deadline:
        need(2)
        opcode, length = buf[0] & 0x0F, buf[1] & 0x7F
        offset = 2
        if length == 126:
            need(4); length = int.from_bytes(buf[2:4], "big"); offset = 4
        elif length == 127:
            need(10); length = int.from_bytes(buf[2:10], "big"); offset = 10
        need(offset + length)
        payload, buf = buf[offset:offset + length], buf[offset + length:]
        if opcode == 8:
            break
        if opcode == 1:
            print(payload.decode(), flush=True)
except (socket.timeout, EOFError):
    pass

"""Connections on real uvicorn over real loopback sockets: a slow-loris client (headers or body a byte at a time) and a
silent one are answered 408 and disconnected once the configured timeout passes, and connections beyond the limit
get 503 — while everyone else is served. (Timeouts are small here; the loops are bounded, nothing is timed.)"""
import json
import select
import socket
import time

import pytest
from portal_fixtures import make_portal

from swarmdeck.console.portal.app import HttpSettings

STEP_S = 0.2  # the slow client's pace: a byte every STEP_S seconds
MAX_STEPS = 300  # ... for at most a minute: far longer than the 1 s timeouts below


@pytest.fixture
def strict(tmp_path):
    p = make_portal(tmp_path, http=HttpSettings(header_timeout_s=1.0, body_timeout_s=1.0, keep_alive_s=30.0,
                                                max_connections=4),
                    fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    try:
        yield p
    finally:
        p.server.stop()
        p.service.close()


def connect(portal) -> socket.socket:
    return socket.create_connection((portal.server.host, portal.server.port), timeout=10)


def drip(sock: socket.socket, data: bytes) -> tuple[int, bytes]:
    """Send ``data`` a byte per STEP_S (then nothing) until the server closes the connection: (bytes sent, what it
    answered). Fails if the connection is still open after MAX_STEPS."""
    answer, sent = b"", 0
    for _step in range(MAX_STEPS):
        readable, _, _ = select.select([sock], [], [], STEP_S)
        if readable:
            try:
                chunk = sock.recv(65536)
            except ConnectionResetError:
                return sent, answer
            if not chunk:
                return sent, answer
            answer += chunk
            continue
        if sent < len(data):
            try:
                sock.sendall(data[sent:sent + 1])
            except (BrokenPipeError, ConnectionResetError):
                return sent, answer
            sent += 1
    raise AssertionError(f"still connected after {MAX_STEPS} steps of {STEP_S} s; sent {sent} bytes")


def test_headers_sent_a_byte_at_a_time_are_cut_off_with_408(strict):
    request = b"GET /api/health HTTP/1.1\r\nHost: x\r\nX-Slow: " + b"a" * 1000 + b"\r\n\r\n"
    with connect(strict) as sock:
        sent, answer = drip(sock, request)
    assert sent < len(request) and answer.startswith(b"HTTP/1.1 408 ")
    with strict.client(None) as c:
        assert c.get("/api/health").json() == {"ok": True}  # the others are served meanwhile and after


def test_a_body_sent_a_byte_at_a_time_is_cut_off_with_408(strict):
    head = b"POST /api/session HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 1000\r\n\r\n"
    with connect(strict) as sock:
        sock.sendall(head)
        sent, answer = drip(sock, b'{"token": "' + b"a" * 2000)
    assert sent < 1000 and answer.startswith(b"HTTP/1.1 408 ")
    assert json.loads(answer.split(b"\r\n\r\n", 1)[1]) == {"error": "the request body did not arrive within 1 s",
                                                              "field": "body"}
    with strict.client(None) as c:
        assert c.get("/api/health").status_code == 200


def test_a_request_answered_before_its_slow_body_is_in_is_disconnected(strict):
    head = (f"POST /api/jobs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer {strict.tokens['alice']}\r\n"
            "Content-Type: application/json\r\nContent-Length: 100000\r\n\r\n").encode()
    with connect(strict) as sock:
        sock.sendall(head)
        sent, answer = drip(sock, b"a" * 2000)
    assert answer.startswith(b"HTTP/1.1 422 ")  # not a form: refused at once, and the rest is not waited for


def test_a_connection_that_sends_nothing_is_closed(strict):
    with connect(strict) as sock:
        sent, answer = drip(sock, b"")
    assert answer.startswith(b"HTTP/1.1 408 ")


def test_connections_beyond_the_limit_get_503_and_the_server_recovers(tmp_path):
    p = make_portal(tmp_path, http=HttpSettings(max_connections=3, header_timeout_s=60.0, keep_alive_s=60.0),
                    fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    held = []
    try:
        for _ in range(2):  # two kept-alive connections, each served once (so the server holds them)
            sock = connect(p)
            sock.sendall(b"GET /api/health HTTP/1.1\r\nHost: x\r\n\r\n")
            assert sock.recv(65536).startswith(b"HTTP/1.1 200 ")
            held.append(sock)
        with p.client(None) as c:
            r = c.get("/api/health")  # the third connection: at the limit
            assert r.status_code == 503
            for sock in held:
                sock.close()
            for _ in range(200):  # the server notices the closes
                if c.get("/api/health", headers={"Connection": "close"}).status_code == 200:
                    break
                time.sleep(0.05)
            else:
                raise AssertionError("the server still refuses after the held connections closed")
    finally:
        for sock in held:
            sock.close()
        p.server.stop()
        p.service.close()


def test_uploads_and_pages_still_work_under_the_limits(strict):
    r = strict.submit("alice")
    assert r.status_code == 201, r.text
    with strict.client("alice") as c:
        assert c.get(f"/api/jobs/{r.json()['id']}").json()["state"] == "awaiting verification"


def test_a_big_upload_with_a_bad_token_gets_its_401(strict):
    with strict.client(None) as c:
        for _ in range(3):
            r = c.post("/api/jobs", headers={"Authorization": "Bearer sdk_revoked-or-wrong"},
                       files={"script": ("big.py", b"#" * (60 << 10))}, data={"manifest": "{}"})
            assert r.status_code == 401 and r.json()["field"] == "Authorization"


def test_a_4_mib_upload_with_a_bad_token_gets_its_401(tmp_path):
    p = make_portal(tmp_path, fleet=6, max_duration=60.0, max_upload_bytes=4 << 20)
    try:
        with p.client(None) as c:
            for _ in range(3):
                r = c.post("/api/jobs", headers={"Authorization": "Bearer sdk_revoked-or-wrong"},
                           files={"script": ("big.py", b"#" * ((4 << 20) - 1000))}, data={"manifest": "{}"})
                assert r.status_code == 401 and r.json()["field"] == "Authorization"
    finally:
        p.server.stop()
        p.service.close()

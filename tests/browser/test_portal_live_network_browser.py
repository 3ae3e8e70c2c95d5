"""The portal's live view (static/live.js in Debian's chromium) draws a decentralised run's communication links
(the Frame's ``network``, the picture's network layer): the page, live.js and a stream of one Frame's message served
over real HTTP on loopback; ``window.swarmdeckLive.links`` counts the links drawn."""

from __future__ import annotations

import json
import os
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import numpy as np
import pytest

from swarmdeck.console.portal.live import scene_message
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.network_frame import NetworkFrame

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
LIVE_JS = Path(__file__).resolve().parents[2] / "console" / "portal" / "static" / "live.js"
pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]

PAGE = (b'<!doctype html><html><body><canvas id="live" width="640" height="400" data-stream="/stream"></canvas>'
        b'<p id="live-status"></p><script src="/live.js"></script></body></html>')


def _message() -> bytes:
    n = 3
    frame = Frame(tick=1, time=0.033, poses=np.array([[-1.0, -0.5, 0.0], [0.0, 0.0, 1.0], [0.8, 0.4, 2.0]]),
                  ids=np.arange(n), nominal=np.zeros((n, 2)), safe=np.zeros((n, 2)), v=np.zeros(n), w=np.zeros(n),
                  network=NetworkFrame(np.array([[0, 1], [1, 2]]), np.array([30.0, 0.0])))
    return json.dumps(scene_message(frame, 1)).encode()


class _Handler(BaseHTTPRequestHandler):
    def log_message(self, *args: object) -> None:
        pass

    def do_GET(self) -> None:  # noqa: N802 - the http.server name
        if self.path == "/stream":
            body = b"event: frame\ndata: " + _message() + b"\n\n"
            self.send_response(200)
            self.send_header("Content-Type", "text/event-stream")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)
            return
        body, kind = (LIVE_JS.read_bytes(), "text/javascript") if self.path == "/live.js" else (PAGE, "text/html")
        self.send_response(200)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)


@pytest.fixture
def server():
    httpd = ThreadingHTTPServer(("127.0.0.1", 0), _Handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}"
    httpd.shutdown()
    httpd.server_close()


def test_the_live_view_draws_the_network_links(server) -> None:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            page = browser.new_page()
            page.goto(server + "/")
            page.wait_for_function("window.swarmdeckLive && window.swarmdeckLive.frames >= 1", timeout=30_000)
            assert page.evaluate("window.swarmdeckLive.links") == 2
        finally:
            browser.close()

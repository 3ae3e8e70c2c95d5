"""The portal's live view alone in a browser: its page and ``live.js`` served over real HTTP on loopback
beside a stream that sends one Frame's message (``console.portal.live.scene_message``), for the browser tests
of what the live view draws."""
from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

from swarmdeck.console.portal.live import scene_message
from swarmdeck.console.runtime.frame import Frame

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
LIVE_JS = Path(__file__).resolve().parents[1] / "console" / "portal" / "static" / "live.js"
#: The canvas of the page, in pixels (live.js fits the arena into it, centred).
WIDTH, HEIGHT = 640, 400
PAGE = (f'<!doctype html><html><body><canvas id="live" width="{WIDTH}" height="{HEIGHT}" data-stream="/stream">'
        f'</canvas><p id="live-status"></p><script src="/live.js"></script></body></html>').encode()


@contextmanager
def live_page(frame: Frame) -> Iterator[str]:
    """Serve the live view streaming ``frame`` (as tick 1); yields the page's URL."""
    message = json.dumps(scene_message(frame, 1)).encode()

    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args: object) -> None:
            pass

        def do_GET(self) -> None:  # noqa: N802 - the http.server name
            if self.path == "/stream":
                body, kind = b"event: frame\ndata: " + message + b"\n\n", "text/event-stream"
            elif self.path == "/live.js":
                body, kind = LIVE_JS.read_bytes(), "text/javascript"
            else:
                body, kind = PAGE, "text/html"
            self.send_response(200)
            self.send_header("Content-Type", kind)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}/"
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join(timeout=10)

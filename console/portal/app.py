"""The portal's ASGI app (FastAPI on uvicorn): ``create_app(service, live=...)``, and :class:`ServerThread`.

* ``/api/...``: the JSON API (:mod:`.api`); ``/docs``: its OpenAPI page
  (``/openapi.json``).
* Upload limits are enforced while the body streams in (:class:`BodyLimit`):
  a request whose ``Content-Length`` is over the limit is answered 413 before
  a byte of its body is read; a body without a length is counted as it
  arrives and cut off with 413 once it passes the limit. The server keeps
  serving everyone else.
* Every error is a JSON ``{"error", "field"}`` with a 4xx status, counted in
  ``app.state.rejections`` (a :class:`~.errors.RejectionCounter`).
* ``app.state.service``, ``app.state.live`` (the :class:`~.livefeed.LiveFeed`)
  and ``app.state.rejections`` are what the pages read.

The pages (``console/portal/pages.py``, researcher and operator HTML, live
view) are included in :func:`create_app` at the line marked ``PAGES``.
"""
from __future__ import annotations

import json
import socket
import threading
from typing import Any

import uvicorn
from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, RedirectResponse
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from swarmdeck.console.portal import pages
from swarmdeck.console.portal.api import api_router
from swarmdeck.console.portal.errors import PortalError, RejectionCounter, TooLarge
from swarmdeck.console.portal.livefeed import LiveFeed
from swarmdeck.console.portal.service import PortalService

FORM_OVERHEAD = 64 << 10  # multipart boundaries, headers and the manifest field on top of the script's bytes


class BodyLimit:
    """ASGI middleware: request bodies larger than ``limit`` bytes get 413 (see the module docstring)."""

    def __init__(self, app: ASGIApp, limit: int, counter: RejectionCounter) -> None:
        self.app, self.limit, self.counter = app, int(limit), counter

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        for name, value in scope.get("headers", ()):
            if name == b"content-length":
                try:
                    length = int(value)
                except ValueError:
                    length = -1
                if length > self.limit or length < 0:
                    await self._refuse(send, f"the request body is {value.decode(errors='replace')} bytes, "
                                             f"more than the limit of {self.limit}")
                    return
        seen = 0
        limit = self.limit

        async def counted() -> Message:
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > limit:
                    raise TooLarge(f"the request body passed the limit of {limit} bytes", "script")
            return message

        await self.app(scope, counted, send)

    async def _refuse(self, send: Send, message: str) -> None:
        error = TooLarge(message, "script")
        self.counter.count(error.status, error.field)
        body = json.dumps(error.to_dict()).encode()
        await send({"type": "http.response.start", "status": error.status,
                    "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
                                (b"connection", b"close")]})
        await send({"type": "http.response.body", "body": body})


def _error_response(counter: RejectionCounter, status: int, message: str, field: str | None) -> JSONResponse:
    counter.count(status, field)
    return JSONResponse({"error": message, "field": field}, status_code=status)


def create_app(service: PortalService, *, live: LiveFeed | None = None,
               rejections: RejectionCounter | None = None) -> FastAPI:
    """The portal app on ``service``; ``live`` is the runner's LiveFeed (a fresh, empty one if None)."""
    counter = rejections if rejections is not None else RejectionCounter()
    limit = service.config.limits.max_upload_bytes
    app = FastAPI(title="swarmdeck portal", version="1",
                  description="Remote access to the swarmdeck arena: submit experiments, follow their "
                              "verification and run, download the data. Authenticate with "
                              "`Authorization: Bearer TOKEN` (from `swarmdeck users add`).",
                  docs_url="/docs", redoc_url=None)
    app.state.service = service
    app.state.live = live if live is not None else LiveFeed()
    app.state.rejections = counter

    @app.exception_handler(PortalError)
    async def portal_error(request: Request, exc: PortalError) -> JSONResponse:
        return _error_response(counter, exc.status, exc.message, exc.field)

    @app.exception_handler(RequestValidationError)
    async def validation_error(request: Request, exc: RequestValidationError) -> JSONResponse:
        first = exc.errors()[0] if exc.errors() else {}
        loc = [str(p) for p in first.get("loc", ()) if p not in ("body", "query", "path")]
        field = loc[-1] if loc else None
        return _error_response(counter, 422, f"{field or 'request'}: {first.get('msg', 'invalid')}", field)

    @app.exception_handler(StarletteHTTPException)
    async def http_error(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        return _error_response(counter, exc.status_code, str(exc.detail), None)

    app.include_router(api_router(service, counter, max_upload_bytes=limit))

    # PAGES: the HTML pages and the live view (console/portal/pages.py) are included here:
    app.include_router(pages.router(service, app.state.live))

    @app.get("/", include_in_schema=False)
    def root() -> RedirectResponse:
        return RedirectResponse("/docs")

    app.add_middleware(BodyLimit, limit=limit + FORM_OVERHEAD, counter=counter)
    return app


def bind(host: str, port: int) -> socket.socket:
    """A listening TCP socket on (host, port); port 0 picks a free one. OSError if it cannot bind."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)  # IPPROTO_TCP: asyncio then sets
    # TCP_NODELAY on each connection (with proto 0 it does not, and every response waits ~40 ms for a delayed ACK)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
        sock.listen(2048)
    except OSError:
        sock.close()
        raise
    sock.set_inheritable(True)
    return sock


def uvicorn_server(app: Any, *, log_level: str = "warning") -> uvicorn.Server:
    """A uvicorn server for ``app`` (HTTP/1.1 via h11; signals left to the caller)."""
    config = uvicorn.Config(app, log_level=log_level, access_log=False, lifespan="off", timeout_graceful_shutdown=2)
    return uvicorn.Server(config)


class ServerThread:
    """uvicorn serving ``app`` on a background thread (tests, benchmarks): ``url``, :meth:`stop`."""

    def __init__(self, app: Any, host: str = "127.0.0.1", port: int = 0) -> None:
        self.sock = bind(host, port)
        self.host, self.port = host, self.sock.getsockname()[1]
        self.url = f"http://{host}:{self.port}"
        self.server = uvicorn_server(app)
        self.thread = threading.Thread(target=self.server.run, kwargs={"sockets": [self.sock]}, daemon=True,
                                       name="swarmdeck-portal-http")
        self.thread.start()
        while not self.server.started and self.thread.is_alive():
            self.thread.join(0.01)

    def stop(self) -> None:
        self.server.should_exit = True
        self.thread.join(10)
        self.sock.close()

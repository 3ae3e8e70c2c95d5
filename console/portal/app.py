"""The portal's ASGI app (FastAPI on uvicorn): ``create_app(service, live=...)``, and :class:`ServerThread`.

* ``/api/...``: the JSON API (:mod:`.api`); ``/docs``: its OpenAPI page, Swagger UI
  served from this server (the assets of the ``fastapi-offline`` package; no CDN,
  no inline script, under a Content-Security-Policy that allows only this origin),
  reading ``/openapi.json``.
* Connections (:class:`HttpSettings`, given to uvicorn by :func:`uvicorn_server`):
  at most ``max_connections`` at once (more get 503); a request's line and
  headers must arrive within ``header_timeout_s`` of the connection opening (or of
  the previous response) and its body within ``body_timeout_s`` of its headers, or
  the connection is closed (408): a client sending a byte a second holds a
  connection for seconds, not forever. Idle keep-alive connections close after
  ``keep_alive_s``. Proxy headers (``X-Forwarded-For``/``-Proto``) are believed
  only from ``trust_proxy`` addresses (default none: the peer's address is the
  client's, whatever a request claims).
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

import asyncio
import json
import socket
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h11
import uvicorn
from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, RedirectResponse, Response
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send
from uvicorn.protocols.http.h11_impl import H11Protocol

from swarmdeck.console.portal import pages
from swarmdeck.console.portal.api import api_router
from swarmdeck.console.portal.errors import PortalError, RejectionCounter, RequestTimeout, TooLarge
from swarmdeck.console.portal.livefeed import LiveFeed
from swarmdeck.console.portal.service import PortalService
from swarmdeck.core.service_thread import ServiceThread

FORM_OVERHEAD = 64 << 10  # multipart boundaries, headers and the manifest field on top of the script's bytes
#: the API page: Swagger UI from this server (no inline script: docs.js starts it), under DOCS_CSP
DOCS_HTML = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>swarmdeck portal API</title>
<link rel="stylesheet" href="/docs/assets/swagger-ui.css"><link rel="icon" href="/docs/assets/favicon.png"></head>
<body><noscript><a href="/openapi.json">openapi.json</a></noscript><div id="swagger-ui" data-url="/openapi.json"></div>
<script src="/docs/assets/swagger-ui-bundle.js"></script><script src="/static/docs.js"></script></body></html>
"""
DOCS_CSP = ("default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'; connect-src 'self'; "
            "frame-ancestors 'none'; form-action 'self'; base-uri 'none'")
DOCS_ASSETS = {"swagger-ui-bundle.js": "text/javascript", "swagger-ui.css": "text/css", "favicon.png": "image/png"}


def docs_assets() -> Path:
    """The folder of Swagger UI's files (the ``fastapi-offline`` package's ``static/``)."""
    import fastapi_offline

    return Path(fastapi_offline.__file__).resolve().parent / "static"


@dataclass(frozen=True)
class HttpSettings:
    """How the portal's HTTP server treats connections (module docstring; ``swarmdeck server`` flags).

    Attributes:
        max_connections: connections (and requests in progress) at once; with this many, a new request gets
            503 (uvicorn's ``limit_concurrency``).
        header_timeout_s: a request line and its headers must arrive within this, s.
        body_timeout_s: a request's body must arrive within this of its headers, s (at the upload limit
            this is the slowest link served: 4 MiB in 120 s ≈ 35 kB/s).
        keep_alive_s: an idle kept-alive connection is closed after this, s.
        trust_proxy: addresses whose ``X-Forwarded-For``/``X-Forwarded-Proto`` are believed (a reverse proxy on
            this machine: ``("127.0.0.1",)``); empty: none.
    """

    max_connections: int = 200
    header_timeout_s: float = 10.0
    body_timeout_s: float = 120.0
    keep_alive_s: float = 5.0
    trust_proxy: tuple[str, ...] = ()


class GuardedH11Protocol(H11Protocol):
    """uvicorn's HTTP/1.1 protocol with deadlines uvicorn lacks (a client sending a byte a second would hold its
    connection forever):

    * a request's line and headers must be in ``header_timeout_s`` after the connection opens, or after data
      of a new request starts arriving — else 408 and the connection is closed;
    * a request answered before its body was in (a refusal: 401, 413, 422 …) has ``body_timeout_s`` for the
      rest of its body to arrive (and be discarded, so the client reads its answer) — else the connection is
      closed.

    An idle kept-alive connection is uvicorn's (``timeout_keep_alive``); a body the app is reading is
    :class:`BodyLimit`'s."""

    header_timeout_s = HttpSettings.header_timeout_s  # set per server by a subclass (uvicorn_server)
    body_timeout_s = HttpSettings.body_timeout_s

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        self._deadline: asyncio.TimerHandle | None = None
        self._deadline_for: str | None = None
        super().connection_made(transport)
        self._arm()

    def data_received(self, data: bytes) -> None:
        super().data_received(data)
        self._arm()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def on_response_complete(self) -> None:
        super().on_response_complete()
        if self.conn.their_state is h11.IDLE:
            self._disarm()  # idle between requests: uvicorn's keep-alive timer applies
        else:
            self._arm()

    def _waiting_for(self) -> str | None:
        if self.transport.is_closing():
            return None
        if self.conn.their_state is h11.IDLE:
            return "headers"
        if self.conn.their_state is h11.SEND_BODY and self.cycle is not None and self.cycle.response_complete:
            return "the rest of the body"
        return None

    def _arm(self) -> None:
        waiting = self._waiting_for()
        if waiting != self._deadline_for:
            self._disarm()
        if waiting is not None and self._deadline is None:
            timeout = self.header_timeout_s if waiting == "headers" else self.body_timeout_s
            self._deadline, self._deadline_for = self.loop.call_later(timeout, self._too_slow, waiting), waiting

    def _disarm(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
        self._deadline, self._deadline_for = None, None

    def _too_slow(self, waiting: str) -> None:
        self._deadline, self._deadline_for = None, None
        if self._waiting_for() != waiting:
            return
        if waiting == "headers":
            body = b"the request's headers did not arrive in time"
            self.transport.write(b"HTTP/1.1 408 Request Timeout\r\ncontent-type: text/plain\r\nconnection: close\r\n"
                                 b"content-length: " + str(len(body)).encode() + b"\r\n\r\n" + body)
        self.transport.close()


class BodyLimit:
    """ASGI middleware: request bodies larger than ``limit`` bytes get 413, bodies still arriving ``timeout_s``
    after their headers get 408 (see the module docstring)."""

    def __init__(self, app: ASGIApp, limit: int, counter: RejectionCounter, timeout_s: float = 120.0) -> None:
        self.app, self.limit, self.counter, self.timeout_s = app, int(limit), counter, float(timeout_s)

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
                    await self._refuse(send, TooLarge(f"the request body is {value.decode(errors='replace')} "
                                                      f"bytes, more than the limit of {self.limit}", "script"))
                    return
        seen, complete = 0, False
        limit, timeout_s = self.limit, self.timeout_s
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout_s
        failure: PortalError | None = None  # what cut the body off: the response says so, whatever the app made of it
        replaced = False

        async def counted() -> Message:
            nonlocal seen, complete, failure
            if complete:  # the body is in: later receive()s wait for the disconnect (streams), unbounded
                return await receive()
            try:
                message = await asyncio.wait_for(receive(), max(0.0, deadline - loop.time()))
            except TimeoutError:
                failure = RequestTimeout(f"the request body did not arrive within {timeout_s:g} s", "body")
                raise failure from None
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > limit:
                    failure = TooLarge(f"the request body passed the limit of {limit} bytes", "script")
                    raise failure
                complete = not message.get("more_body", False)
            return message

        async def answer(message: Message) -> None:
            # FastAPI turns an error while it parses a JSON body into 400 "error parsing the body": the client is
            # told the real reason (408/413), and the connection is closed (the rest of the body is not awaited)
            nonlocal replaced
            if failure is not None and message["type"] == "http.response.start" and \
                    message.get("status") != failure.status:
                replaced = True
                await self._refuse(send, failure)
                return
            if replaced:
                return
            await send(message)

        await self.app(scope, counted, answer)

    async def _refuse(self, send: Send, error: PortalError) -> None:
        self.counter.count(error.status, error.field)
        body = json.dumps(error.to_dict()).encode()
        await send({"type": "http.response.start", "status": error.status,
                    "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
                                (b"connection", b"close")]})
        await send({"type": "http.response.body", "body": body})


def _error_response(counter: RejectionCounter, status: int, message: str, field: str | None) -> JSONResponse:
    counter.count(status, field)
    # 408/413: the rest of the body may still be on its way; closing is the only way to be rid of it
    headers = {"connection": "close"} if status in (408, 413) else None
    return JSONResponse({"error": message, "field": field}, status_code=status, headers=headers)


def create_app(service: PortalService, *, live: LiveFeed | None = None,
               rejections: RejectionCounter | None = None, http: HttpSettings | None = None) -> FastAPI:
    """The portal app on ``service``; ``live`` is the runner's LiveFeed (a fresh, empty one if None); ``http``
    the body timeout (the rest of :class:`HttpSettings` is uvicorn's, :func:`uvicorn_server`)."""
    http = http if http is not None else HttpSettings()
    counter = rejections if rejections is not None else RejectionCounter()
    limit = service.config.limits.max_upload_bytes
    app = FastAPI(title="swarmdeck portal", version="1",
                  description="Remote access to the swarmdeck arena: submit experiments, follow their "
                              "verification and run, download the data. Authenticate with "
                              "`Authorization: Bearer TOKEN` (from `swarmdeck users add`).",
                  docs_url=None, redoc_url=None)
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

    app.add_exception_handler(pages.SignInRequired, pages.to_signin_page)  # a page behind sign-in, signed out

    @app.exception_handler(StarletteHTTPException)
    async def http_error(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        return _error_response(counter, exc.status_code, str(exc.detail), None)

    app.include_router(api_router(service, counter, max_upload_bytes=limit))

    # PAGES: the HTML pages and the live view (console/portal/pages.py) are included here:
    app.include_router(pages.router(service, app.state.live))

    @app.get("/", include_in_schema=False)
    def root() -> RedirectResponse:
        return RedirectResponse("/docs")

    @app.get("/docs", include_in_schema=False)
    def docs() -> HTMLResponse:
        return HTMLResponse(DOCS_HTML, headers={"Content-Security-Policy": DOCS_CSP, "Cache-Control": "no-cache",
                                                "X-Content-Type-Options": "nosniff", "Referrer-Policy": "same-origin"})

    assets = docs_assets()

    @app.get("/docs/assets/{name}", include_in_schema=False)
    def docs_asset(name: str) -> Response:
        if name not in DOCS_ASSETS:
            return Response("not found", status_code=404, media_type="text/plain")
        return FileResponse(assets / name, media_type=DOCS_ASSETS[name],
                            headers={"Cache-Control": "max-age=86400", "X-Content-Type-Options": "nosniff"})

    app.add_middleware(BodyLimit, limit=limit + FORM_OVERHEAD, counter=counter, timeout_s=http.body_timeout_s)
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


def uvicorn_server(app: Any, *, log_level: str = "warning", http: HttpSettings | None = None) -> uvicorn.Server:
    """A uvicorn server for ``app`` (HTTP/1.1 via h11 with the header deadline of :class:`GuardedH11Protocol`;
    signals left to the caller), its connections as ``http`` says (default :class:`HttpSettings`)."""
    http = http if http is not None else HttpSettings()
    protocol = type("PortalH11Protocol", (GuardedH11Protocol,), {"header_timeout_s": float(http.header_timeout_s),
                                                                "body_timeout_s": float(http.body_timeout_s)})
    config = uvicorn.Config(app, log_level=log_level, access_log=False, lifespan="off", timeout_graceful_shutdown=2,
                            http=protocol, limit_concurrency=int(http.max_connections),
                            timeout_keep_alive=float(http.keep_alive_s),
                            proxy_headers=bool(http.trust_proxy), forwarded_allow_ips=list(http.trust_proxy) or [])
    return uvicorn.Server(config)


class ServerThread:
    """uvicorn serving ``app`` on a background thread (tests, benchmarks): ``url``, :meth:`stop`."""

    def __init__(self, app: Any, host: str = "127.0.0.1", port: int = 0, http: HttpSettings | None = None) -> None:
        self.sock = bind(host, port)
        self.host, self.port = host, self.sock.getsockname()[1]
        self.url = f"http://{host}:{self.port}"
        self.server = uvicorn_server(app, http=http)
        self.thread = ServiceThread(self._serve, "swarmdeck-portal-http", join_timeout=10.0, wake=self._exit).start()
        while not self.server.started and self.thread.alive:
            self.thread.wait(0.01)

    def _serve(self) -> None:
        self.server.run(sockets=[self.sock])

    def _exit(self) -> None:
        self.server.should_exit = True

    def stop(self) -> None:
        """Shut the server down (its connections get ``timeout_graceful_shutdown``), join it, close the socket."""
        self.thread.stop()
        self.sock.close()

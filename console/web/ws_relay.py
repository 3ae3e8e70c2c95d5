"""A WebSocket front door that speaks both names of the Foxglove WebSocket protocol.

The official ``foxglove-sdk`` server (0.30) accepts only the subprotocol
``foxglove.sdk.v1`` and answers HTTP 400 to ``foxglove.websocket.v1``, the name
the official ``@foxglove/ws-protocol`` client, older Foxglove apps, Lichtblick
and most third-party clients ask for. The two names denote the same protocol
(Foxglove's ws-protocol spec; the SDK renamed it), so :class:`SubprotocolRelay`
listens on the public address, accepts either name (answering with the one the
client asked for) and relays every WebSocket message unchanged, in both
directions, to the SDK server on a private loopback port. One connection to the
SDK per client; when either side closes, so does the other.

It runs an asyncio loop on its own daemon thread; a busy port is an ``OSError``
(``errno.EADDRINUSE``) at construction.
"""
from __future__ import annotations

import asyncio
from typing import Any

from swarmdeck.core.service_thread import ServiceThread

#: The names a client may ask for, the SDK's own first (REFERENCE.md §13).
SUBPROTOCOLS: tuple[str, ...] = ("foxglove.sdk.v1", "foxglove.websocket.v1")
UPSTREAM_SUBPROTOCOL = "foxglove.sdk.v1"


class SubprotocolRelay:
    """Relay Foxglove WebSocket clients of either subprotocol to an SDK server at ``upstream_port``.

    Args:
        host: interface to listen on.
        port: TCP port (0 picks a free one; see :attr:`port`).
        upstream_port: the SDK server's port on 127.0.0.1.
    """

    def __init__(self, host: str, port: int, upstream_port: int) -> None:
        self.upstream = f"ws://127.0.0.1:{int(upstream_port)}"
        self.clients = 0  # connected now
        self.served = 0  # connections relayed so far
        self.refused = 0  # clients that asked for another protocol (HTTP 400)
        self._loop = asyncio.new_event_loop()
        self._service = ServiceThread(self._loop.run_forever, "swarmdeck-foxglove-relay", join_timeout=5.0,
                                      wake=lambda: self._loop.call_soon_threadsafe(self._loop.stop))
        self._service.start()
        try:
            self._server = asyncio.run_coroutine_threadsafe(self._serve(host, port), self._loop).result(10.0)
        except BaseException:
            self._stop_loop()
            raise
        self.port: int = int(self._server.sockets[0].getsockname()[1])

    async def _serve(self, host: str, port: int) -> Any:
        from websockets.asyncio.server import serve

        return await serve(self._handle, host, port, subprotocols=list(SUBPROTOCOLS),  # type: ignore[arg-type]
                           select_subprotocol=_select, process_request=self._check, compression=None,
                           max_size=None)

    def _check(self, connection: Any, request: Any) -> Any:
        """Refuse (HTTP 400 naming the subprotocols, counted in :attr:`refused`) a client asking for none of
        :data:`SUBPROTOCOLS`, before the handshake: no traceback in the console's log."""
        offered = {p.strip() for h in request.headers.get_all("Sec-WebSocket-Protocol") for p in h.split(",")}
        if offered & set(SUBPROTOCOLS):
            return None
        self.refused += 1
        return connection.respond(400, f"Foxglove WebSocket: ask for the subprotocol {' or '.join(SUBPROTOCOLS)}\n")

    async def _handle(self, client: Any) -> None:
        from websockets.asyncio.client import connect
        from websockets.exceptions import ConnectionClosed

        try:
            upstream = await connect(self.upstream, subprotocols=[UPSTREAM_SUBPROTOCOL],  # type: ignore[list-item]
                                     compression=None, max_size=None, proxy=None)
        except (TimeoutError, OSError, ConnectionClosed) as exc:
            await client.close(1011, f"Foxglove server unavailable: {type(exc).__name__}")
            return
        self.clients += 1
        self.served += 1

        async def pump(src: Any, dst: Any) -> None:
            try:
                async for message in src:
                    await dst.send(message)
            except ConnectionClosed:
                pass
            finally:
                await dst.close()

        try:
            await asyncio.gather(pump(client, upstream), pump(upstream, client))
        finally:
            self.clients -= 1

    def _stop_loop(self) -> None:
        if self._service.stop():
            self._loop.close()

    def close(self) -> None:
        """Stop listening, close every relayed connection and the thread. Idempotent."""
        if self._loop.is_closed():
            return

        async def shut() -> None:
            self._server.close()
            await self._server.wait_closed()

        try:
            asyncio.run_coroutine_threadsafe(shut(), self._loop).result(10.0)
        except Exception:  # noqa: BLE001 - closing must not fail the console's exit
            pass
        self._stop_loop()


def _select(connection: Any, offered: Any) -> Any:
    """The first name the client offered that is one of :data:`SUBPROTOCOLS` (others were refused before)."""
    return next((p for p in offered if p in SUBPROTOCOLS), None)

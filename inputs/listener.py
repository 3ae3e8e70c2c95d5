"""Input sources: the socket-free core (:class:`InputSource`) and thin socket
listeners with lifetimes (:class:`UdpListener`, :class:`TcpListener`).

Every datagram — from a socket or from a recording — goes through
:meth:`InputSource.feed`: the ``on_datagram`` hook (for the recorder) sees the raw
bytes first, then the datagram is parsed whole, decoded (TUIO 1.1/2.0, OSC point
streams) and applied to the contact table. Malformed input is counted per
source with a clear reason; nothing raises out of ``feed`` or the socket threads.
One lock serialises ``feed`` and ``poll`` so the console thread always sees a
consistent snapshot.
"""
from __future__ import annotations

import fnmatch
import functools
import math
import socket
import struct
import threading
import time
from collections.abc import Callable

from swarmdeck.core.service_thread import ServiceThread

from .calibration import Calibration
from .config import ListenerConfig
from .contact import Contact, InputSnapshot, InputWork, SourceHealth
from .contacts import ContactTable, HealthBook
from .oscparse import MalformedDatagram, parse_datagram
from .pointstream import PointStreamDecoder
from .tuio import TuioAssembler

#: ``hook(data, peer, transport, t)``, called for every datagram before parsing.
DatagramHook = Callable[[bytes, object, str, float], None]

BIG_DATAGRAM = 8192
CLOCK_TOLERANCE = 0.5  # s between a socket listener's clock and the time it is polled at
_LEN = struct.Struct(">I")


def peer_name(transport: str, peer: object) -> str:
    """``"udp://10.0.0.2:50000"`` from a ``(host, port)`` peer; strings pass through
    (with the transport prefixed unless they already have a scheme)."""
    if isinstance(peer, (tuple, list)) and len(peer) >= 2:
        return f"{transport}://{peer[0]}:{peer[1]}"
    s = str(peer)
    return s if "://" in s else f"{transport}://{s}"


def sender_name(transport: str, peer: object) -> str:
    """The sending host without its port: ``"udp://10.0.0.2"`` from ``("10.0.0.2",
    50000)`` or ``"udp://10.0.0.2:50000"`` (IPv6 hosts in brackets).

    Input state is keyed by this, not by the UDP/TCP port: every ``oscsend`` run and
    every TCP reconnect comes from a new port but is the same sender. TUIO sources
    are further told apart by their ``source`` string."""
    if isinstance(peer, (tuple, list)) and len(peer) >= 2:
        scheme, host = transport, str(peer[0])
    else:
        s = str(peer)
        scheme, _, rest = s.partition("://") if "://" in s else (transport, "", s)
        if rest.startswith("["):
            host = rest[:rest.index("]") + 1] if "]" in rest else rest
        elif rest.count(":") == 1:
            host = rest.rsplit(":", 1)[0]
        else:
            host = rest
    if ":" in host and not host.startswith("["):
        host = f"[{host}]"
    return f"{scheme}://{host}"


class InputSource:
    """Datagrams in; contacts, events and health out. No sockets.

    Args:
        config: ports are ignored here; decoders, calibration and timeout are used.
        on_datagram: recorder hook ``(data, peer, transport, t)``.
        wallclock: Unix-seconds clock for future-timetag checks (bundle timetags
            are never waited for).
    """

    def __init__(self, config: ListenerConfig | None = None, *, on_datagram: DatagramHook | None = None,
                 wallclock: Callable[[], float] = time.time) -> None:
        self.config = config or ListenerConfig()
        self.on_datagram = on_datagram
        self._wallclock = wallclock
        self._lock = threading.Lock()
        cfg = self.config
        forget_after = max(cfg.forget_after, cfg.timeout)
        self._health = HealthBook(forget_after=forget_after, name=f"listener {cfg.name}")
        self._peer_names: dict = {}
        self._tuio = TuioAssembler(self._health, max_contacts=cfg.max_contacts_per_source) if cfg.tuio else None
        self._points = PointStreamDecoder(cfg.streams, self._health)
        self._table = ContactTable(self._calibration_for, cfg.timeout, on_lost=self._forget,
                                   max_per_source=cfg.max_contacts_per_source, max_total=cfg.max_contacts,
                                   max_events=cfg.max_events, forget_after=forget_after, problems=self._health)
        self._arguments_decoded = 0

    @property
    def name(self) -> str:
        """The listener's configured name (``ListenerConfig.name``)."""
        return self.config.name

    # ------------------------------------------------------------------ helpers
    def _calibration_for(self, name: str) -> Calibration:
        for pattern, cal in self.config.source_calibrations:
            if fnmatch.fnmatchcase(name, pattern):
                return cal
        return self.config.calibration

    def _forget(self, name: str) -> None:
        if self._tuio is not None:
            self._tuio.forget(name)
        self._points.forget(name)

    # ------------------------------------------------------------------ data in
    def feed(self, data: bytes, peer: object, t: float, transport: str | None = None) -> None:
        """Process one datagram received from ``peer`` at time ``t`` (s, the
        console's clock — virtual in tests and replays). Never raises."""
        transport = transport or self.config.transport
        try:
            data = bytes(data)
            t = float(t)
        except (TypeError, ValueError) as exc:
            with self._lock:
                self._health.error(sender_name(transport, peer), "peer", "bad_feed",
                                   f"feed() needs bytes and a time in s: {exc}")
            return
        if not math.isfinite(t):
            with self._lock:
                self._health.error(sender_name(transport, peer), "peer", "bad_feed",
                                   f"feed() receive time must be finite, got {t}")
            return
        with self._lock:
            self._feed(data, peer, t, transport)

    def _feed(self, data: bytes, peer: object, t: float, transport: str) -> None:
        key = (transport, peer) if isinstance(peer, (tuple, str)) else None
        pname = self._peer_names.get(key) if key is not None else None
        if pname is None:
            pname = sender_name(transport, peer)
            if key is not None:
                if len(self._peer_names) > 4096:
                    self._peer_names.clear()
                self._peer_names[key] = pname
        health = self._health
        hook = self.on_datagram
        if hook is not None:
            try:
                hook(data, peer, transport, t)
            except Exception as exc:  # a recorder bug must not stop input
                health.error(pname, "peer", "hook_error", f"on_datagram hook raised {type(exc).__name__}: {exc}")
        health.datagram(t)
        health.seen(pname, "peer", t)
        try:
            parsed = parse_datagram(data, self.config.max_datagram, self.config.max_osc_arguments)
        except MalformedDatagram as exc:
            health.error(pname, "peer", exc.reason, str(exc))
            return
        self._arguments_decoded += parsed.cost
        try:
            if len(data) > BIG_DATAGRAM:
                health.warn(pname, "peer", "over_8KiB")
            if parsed.timetag is not None and parsed.timetag > self._wallclock() + self.config.future_tolerance:
                health.warn(pname, "peer", "future_timetag")
            tuio = self._tuio
            points = self._points
            if tuio is not None:
                tuio.begin(pname)
            points.begin(pname)
            rest = tuio.messages(parsed.messages) if tuio is not None else parsed.messages
            for address, params in rest:
                if not points.message(address, params):
                    health.warn(pname, "peer", "unmatched_address")
            frames = tuio.end() if tuio is not None else []
            frames.extend(points.end())
            table = self._table
            for f in frames:
                health.seen(f.source, f.kind, t)
                table.apply(f, t)
        except Exception as exc:  # never let a bug in a decoder escape into the listener thread
            health.error(pname, "peer", "internal_error", f"{type(exc).__name__}: {exc}")

    # ------------------------------------------------------------------ data out
    def _expire(self, now: float) -> dict[str, int]:
        """Expire contacts, forget idle sources (and their decoder state); the
        contact counts of the sources that have some."""
        self._table.expire(now)
        counts = self._table.counts()
        for name in self._health.expire(now, counts.__contains__):
            self._forget(name)
        return counts

    def _totals(self, now: float) -> SourceHealth:
        return self._health.totals(now, len(self._table), events_dropped=self._table.events_dropped,
                                   sources_forgotten=self._health.forgotten)

    def poll(self, now: float) -> InputSnapshot:
        """Expire silent sources and forget idle ones as of ``now``, then return the
        contacts, the events since the previous poll and the health: the listener's
        lifetime totals (kind ``"listener"``) and at most ``max_reported_sources``
        sources (plus one ``"N more sources"`` record when some are left out)."""
        with self._lock:
            counts = self._expire(now)
            health = self._health.snapshot(now, counts, self._table.is_lost, self.config.max_reported_sources)
            return InputSnapshot(now, self._table.contacts(), tuple(self._table.drain_events()),
                                 (self._totals(now),) + health)

    def contacts(self) -> tuple[Contact, ...]:
        """Current contacts (without expiring or draining events)."""
        with self._lock:
            return self._table.contacts()

    def health(self, now: float) -> tuple[SourceHealth, ...]:
        """The listener's totals and the health of every source it holds, as of
        ``now`` (without expiring; unlike :meth:`poll`, not capped)."""
        with self._lock:
            return (self._totals(now),) + self._health.snapshot(now, self._table.counts(), self._table.is_lost)

    def work(self) -> InputWork:
        """Lifetime work counters (see :class:`InputWork`)."""
        with self._lock:
            tot = self._health.totals(0.0, 0)
            return InputWork(tot.datagrams, self._arguments_decoded, len(self._table),
                             tot.errors.get("too_many_contacts", 0), self._table.events_total,
                             self._table.events_dropped, len(self._health), self._health.forgotten)

    def poll_time(self, now: float) -> float:
        """The time to poll this source at: ``now`` for the socket-free core (its
        times are whatever ``feed`` was given); socket listeners override this
        with a reading of their receive clock."""
        return now

    def _check_clock(self, clock: Callable[[], float], now: float, address: object, transport: str) -> None:
        """Receive times come from ``clock``; polling with another time base would
        break timeouts (a ghost finger that never expires). Count it loudly."""
        skew = clock() - now
        if abs(skew) > CLOCK_TOLERANCE:
            with self._lock:
                self._health.error(self._health.name, "listener", "clock_mismatch",
                                   f"poll(now={now:.3f}) is {skew:+.3f} s off this listener's receive clock; "
                                   "build the listener/hub with clock= the loop's clock")

    # lifetimes are no-ops for the socket-free core
    def start(self) -> InputSource:
        """Nothing to start without a socket."""
        return self

    def close(self) -> None:
        """Nothing to close without a socket."""

    def __enter__(self) -> InputSource:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()


class UdpListener(InputSource):
    """An :class:`InputSource` fed by one UDP socket on a background thread.

    Datagrams are read whole (up to 65 536 bytes: nothing is silently truncated)
    and stamped with ``clock()`` on receipt. ``start()`` binds; ``close()`` stops
    the thread and closes the socket. ``address`` is the bound ``(host, port)``.
    """

    def __init__(self, config: ListenerConfig | None = None, *, clock: Callable[[], float] = time.monotonic,
                 on_datagram: DatagramHook | None = None, wallclock: Callable[[], float] = time.time) -> None:
        super().__init__(config, on_datagram=on_datagram, wallclock=wallclock)
        self._clock = clock
        self._sock: socket.socket | None = None
        self._service = ServiceThread(self._run, "swarmdeck-udp")
        self.address: tuple[str, int] | None = None

    def start(self) -> UdpListener:
        """Bind the socket and start the receive thread (idempotent)."""
        if self._service.started:
            return self
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
            sock.bind((self.config.host, self.config.port))
        except OSError as exc:
            sock.close()
            raise OSError(exc.errno, f"cannot bind UDP {self.config.host}:{self.config.port} for input "
                                     f"{self.config.name!r}: {exc.strerror}") from None
        sock.settimeout(0.05)
        self._sock = sock
        self.address = sock.getsockname()[:2]
        with self._lock:
            self._health.name = f"listener {self.config.name} {peer_name(self.config.transport, self.address)}"
        self._service.name = f"swarmdeck-udp-{self.address[1]}"
        self._service.start()
        return self

    def _run(self) -> None:
        sock = self._sock
        assert sock is not None
        svc = self._service
        while not svc.stopping:
            try:
                data, addr = sock.recvfrom(65536)
            except TimeoutError:
                continue
            except OSError as exc:
                if svc.stopping:
                    break
                with self._lock:
                    self._health.error(self._health.name, "listener", "socket_error", str(exc))
                svc.wait(0.05)
                continue
            self.feed(data, addr, self._clock(), "udp")

    def poll_time(self, now: float) -> float:
        """This listener's receive clock (``now`` is ignored)."""
        return self._clock()

    def poll(self, now: float) -> InputSnapshot:
        """As :meth:`InputSource.poll`; ``now`` must be on this listener's ``clock``
        (a mismatch is counted as ``clock_mismatch`` on the listener's own entry).
        :class:`InputHub` always polls listeners on their own clock."""
        if self.address is not None:
            self._check_clock(self._clock, now, self.address, "udp")
        return super().poll(now)

    def close(self) -> None:
        """Stop the thread and close the socket (idempotent)."""
        self._service.stop()
        if self._sock is not None:
            self._sock.close()
            self._sock = None


class TcpListener(InputSource):
    """TUIO/TCP: accepts connections; each carries OSC packets preceded by their
    4-byte big-endian length (OSC 1.0 stream framing, the reference
    ``TcpSender``). One thread accepts, one thread per connection reads. A length
    of 0 or above ``max_datagram`` is counted and closes that connection."""

    def __init__(self, config: ListenerConfig | None = None, *, clock: Callable[[], float] = time.monotonic,
                 on_datagram: DatagramHook | None = None, wallclock: Callable[[], float] = time.time) -> None:
        super().__init__(config, on_datagram=on_datagram, wallclock=wallclock)
        self._clock = clock
        self._sock: socket.socket | None = None
        self._acceptor = ServiceThread(self._accept, "swarmdeck-tcp")
        self._readers: list[ServiceThread] = []
        self._conns: set[socket.socket] = set()
        self._conn_lock = threading.Lock()
        self.address: tuple[str, int] | None = None

    def start(self) -> TcpListener:
        """Bind, listen and start the accept thread (idempotent)."""
        if self._sock is not None:
            return self
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((self.config.host, self.config.port))
            sock.listen(8)
        except OSError as exc:
            sock.close()
            raise OSError(exc.errno, f"cannot listen on TCP {self.config.host}:{self.config.port} for input "
                                     f"{self.config.name!r}: {exc.strerror}") from None
        sock.settimeout(0.05)
        self._sock = sock
        self.address = sock.getsockname()[:2]
        with self._lock:
            self._health.name = f"listener {self.config.name} {peer_name(self.config.transport, self.address)}"
        self._acceptor.name = f"swarmdeck-tcp-{self.address[1]}"
        self._acceptor.start()
        return self

    def _accept(self) -> None:
        svc = self._acceptor
        while not svc.stopping:
            try:
                conn, addr = self._sock.accept()  # type: ignore[union-attr]
            except TimeoutError:
                continue
            except OSError:
                if svc.stopping:
                    break
                svc.wait(0.05)
                continue
            conn.settimeout(0.05)
            with self._conn_lock:
                self._readers = [r for r in self._readers if r.alive]
                self._conns.add(conn)
                reader = ServiceThread(functools.partial(self._read, conn, addr), f"swarmdeck-tcp-{addr[0]}:{addr[1]}")
                self._readers.append(reader)
            reader.start()

    def _read(self, conn: socket.socket, addr: tuple) -> None:
        buf = bytearray()
        pname = sender_name("tcp", addr)
        limit = self.config.max_datagram
        try:
            while not self._acceptor.stopping:  # one stop for the acceptor and every connection
                try:
                    chunk = conn.recv(65536)
                except TimeoutError:
                    continue
                except OSError:
                    break
                if not chunk:
                    break
                buf += chunk
                while len(buf) >= 4:
                    (n,) = _LEN.unpack_from(buf, 0)
                    if n == 0 or n > limit:
                        with self._lock:
                            self._health.error(pname, "peer", "bad_frame_length",
                                               f"TUIO/TCP length prefix {n} is not in 1..{limit}; connection closed")
                        return
                    if len(buf) < 4 + n:
                        break
                    packet = bytes(buf[4:4 + n])
                    del buf[:4 + n]
                    self.feed(packet, addr, self._clock(), "tcp")
        finally:
            with self._conn_lock:
                self._conns.discard(conn)
            conn.close()

    def poll_time(self, now: float) -> float:
        """This listener's receive clock (``now`` is ignored)."""
        return self._clock()

    def poll(self, now: float) -> InputSnapshot:
        """As :meth:`InputSource.poll`; ``now`` must be on this listener's ``clock``."""
        if self.address is not None:
            self._check_clock(self._clock, now, self.address, "tcp")
        return super().poll(now)

    def close(self) -> None:
        """Stop all threads, close the connections and the listening socket."""
        self._acceptor.stop()
        with self._conn_lock:
            readers, self._readers = self._readers, []
        for r in readers:
            r.stop()
        with self._conn_lock:
            for c in self._conns:
                c.close()
            self._conns.clear()
        if self._sock is not None:
            self._sock.close()
            self._sock = None


def make_listener(config: ListenerConfig, *, clock: Callable[[], float] = time.monotonic,
                  on_datagram: DatagramHook | None = None) -> UdpListener | TcpListener:
    """The listener class for ``config.transport`` (not started)."""
    cls = UdpListener if config.transport == "udp" else TcpListener
    return cls(config, clock=clock, on_datagram=on_datagram)

"""One MQTT connection with automatic reconnection, visible state and counted failures.

A thin lifetime class around a paho-mqtt 2.x client running its network
thread: it connects asynchronously (a broker that is down at start-up is not an
error: the link keeps trying), reconnects with exponential back-off
(``reconnect_min`` doubling to ``reconnect_max``), re-subscribes after every
connection, and never lets an exception out of a paho callback. Publishing
while disconnected drops the message and returns False (never queues stale
robot commands for later).
"""
from __future__ import annotations

import socket
import ssl
import threading
import time
from collections.abc import Callable, Sequence

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from swarmdeck.devices.net.mqtt_config import MqttConfig
from swarmdeck.devices.net.transport import Counters

MessageHandler = Callable[[str, bytes, float], None]


class MqttLink:
    """A connection to the broker for one swarmdeck node.

    Args:
        config: broker, credentials, TLS, QoS, protocol, back-off.
        subscriptions: topic filters subscribed after every (re)connection.
        on_message: ``handler(topic, payload, receive_time)``; exceptions are caught and counted.
        counters: where failures are counted (``connect_failed``, ``connect_refused``,
            ``disconnects``, ``handler_errors``, ``publish_failed``).
        name: used in the client id and in messages.
        clock: monotonic clock for receive times.
    """

    def __init__(
        self,
        config: MqttConfig,
        *,
        subscriptions: Sequence[str] = (),
        on_message: MessageHandler | None = None,
        counters: Counters | None = None,
        name: str = "swarmdeck",
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.config = config
        self.name = name
        self.counters = counters if counters is not None else Counters()
        self._subscriptions = list(subscriptions)
        self._handler = on_message
        self._clock = clock
        self._lock = threading.Lock()
        self._connected = False
        self._state = f"connecting to {config.url}"
        self._closed = False
        self._refused = False
        self.connections = 0
        self._connected_event = threading.Event()  # connected and every subscription acknowledged
        self._pending_subs: set[int] = set()
        v5 = config.protocol == "5"
        self._client = mqtt.Client(
            CallbackAPIVersion.VERSION2,
            client_id=config.client_id,
            protocol=mqtt.MQTTv5 if v5 else mqtt.MQTTv311,
            clean_session=None if v5 else True,
        )
        if config.username is not None:
            self._client.username_pw_set(config.username, config.password)
        if config.tls:
            try:
                self._client.tls_set(
                    ca_certs=config.ca_certs, certfile=config.certfile, keyfile=config.keyfile,
                    cert_reqs=ssl.CERT_REQUIRED, tls_version=ssl.PROTOCOL_TLS_CLIENT,
                )
            except (OSError, ssl.SSLError) as exc:  # missing/unreadable/invalid certificate or key files
                files = {k: v for k, v in (("ca_certs", config.ca_certs), ("certfile", config.certfile),
                                           ("keyfile", config.keyfile)) if v}
                raise ValueError(f"TLS set-up for {config.url} failed with {files}: "
                                 f"{getattr(exc, 'strerror', None) or exc}") from exc
        self._client.reconnect_delay_set(config.reconnect_min, config.reconnect_max)  # type: ignore[arg-type]
        self._client.max_queued_messages_set(1000)
        self._client.on_connect = self._on_connect
        self._client.on_connect_fail = self._on_connect_fail
        self._client.on_disconnect = self._on_disconnect
        self._client.on_message = self._on_message
        self._client.on_subscribe = self._on_subscribe
        self._expiry: Properties | None = None
        if v5:  # commands older than 1 s are useless: let the broker drop them
            self._expiry = Properties(PacketTypes.PUBLISH)
            self._expiry.MessageExpiryInterval = 1

    # ---------------------------------------------------------------- lifetime
    def start(self) -> MqttLink:
        """Start connecting in the background (returns at once)."""
        try:
            if self.config.protocol == "5":
                self._client.connect_async(self.config.host, self.config.port, self.config.keepalive, clean_start=True)
            else:
                self._client.connect_async(self.config.host, self.config.port, self.config.keepalive)
        except (OSError, ValueError) as exc:  # e.g. unresolvable host name
            self._set_state(False, f"cannot connect to {self.config.url}: {exc}")
            self.counters.add("connect_failed", self._state)
        self._client.loop_start()
        return self

    def wait_connected(self, timeout: float) -> bool:
        """Block until connected with every subscription active, or ``timeout`` s passed; True when so."""
        return self._connected_event.wait(timeout)

    def close(self) -> None:
        """Disconnect cleanly and stop the network thread (idempotent)."""
        if self._closed:
            return
        self._closed = True
        try:
            self._client.disconnect()
        except Exception:  # noqa: BLE001 - closing must never raise
            pass
        self._client.loop_stop()
        self._set_state(False, "closed")

    # ---------------------------------------------------------------- state
    @property
    def connected(self) -> bool:
        return self._connected

    @property
    def state(self) -> str:
        return self._state

    def _set_state(self, connected: bool, state: str) -> None:
        with self._lock:
            self._connected = connected
            self._state = state
            if connected and not self._pending_subs:
                self._connected_event.set()
            elif not connected:
                self._connected_event.clear()

    # ---------------------------------------------------------------- publishing
    def publish(self, topic: str, payload: bytes, *, expire: bool = False, qos: int | None = None) -> bool:
        """Publish one message; False (and counted) when it cannot be handed to the broker now."""
        if not self._connected:
            return False
        try:
            info = self._client.publish(topic, payload, qos=self.config.qos if qos is None else qos,
                                        properties=self._expiry if expire else None)
        except (ValueError, OSError) as exc:
            self.counters.add("publish_failed", f"publish to {topic} failed: {exc}")
            return False
        if info.rc != mqtt.MQTT_ERR_SUCCESS:
            self.counters.add("publish_failed", f"publish to {topic} failed: {mqtt.error_string(info.rc)}")
            return False
        return True

    def publish_many(self, topics: Sequence[str], payloads: Sequence[bytes], *, expire: bool = False) -> int:
        """Publish pairs in order; returns how many were handed to the broker (stops at the first failure)."""
        if not self._connected:
            return 0
        sent = 0
        for topic, payload in zip(topics, payloads):  # one message per robot is the wire format
            if not self.publish(topic, payload, expire=expire):
                break
            sent += 1
        return sent

    # ---------------------------------------------------------------- paho callbacks
    def _on_connect(self, client: mqtt.Client, userdata: object, flags: object, reason: object, props: object) -> None:
        try:
            if getattr(reason, "is_failure", False):
                msg = f"broker {self.config.url} refused the connection: {reason}"
                self.counters.add("connect_refused", msg)
                self._refused = True
                self._set_state(False, msg + f"; retrying (up to every {self.config.reconnect_max:g} s)")
                return
            self._refused = False
            self._no_delay(client)
            with self._lock:
                self._pending_subs = set()
                for topic in self._subscriptions:
                    rc, mid = client.subscribe(topic, qos=self.config.qos)
                    if rc == mqtt.MQTT_ERR_SUCCESS and mid is not None:
                        self._pending_subs.add(mid)
            self.connections += 1
            if self.connections > 1:
                self.counters.add("reconnects")
            self._set_state(True, f"connected to {self.config.url}")
        except Exception as exc:  # noqa: BLE001 - never raise into paho's thread
            self.counters.add("handler_errors", f"on_connect failed: {exc!r}")

    @staticmethod
    def _no_delay(client: mqtt.Client) -> None:
        """Turn off Nagle's algorithm: small command messages must leave at once, not wait for an ACK."""
        sock = client.socket()
        try:
            if sock is not None:
                raw = getattr(sock, "_socket", sock)
                raw.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)  # type: ignore[union-attr]  # paho's socket, maybe wrapped (AttributeError is caught)
        except (OSError, AttributeError):  # e.g. a TLS or websocket wrapper without the option
            pass

    def _on_subscribe(self, client: mqtt.Client, userdata: object, mid: int, reasons: object, props: object) -> None:
        for r in reasons if isinstance(reasons, list) else []:
            if getattr(r, "is_failure", False):
                self.counters.add("subscribe_refused", f"broker {self.config.url} refused a subscription: {r}")
        with self._lock:
            self._pending_subs.discard(mid)
            ready = self._connected and not self._pending_subs
        if ready:
            self._connected_event.set()

    def _on_connect_fail(self, client: mqtt.Client, userdata: object) -> None:
        msg = f"cannot reach broker {self.config.url} (connection refused or timed out); retrying with back-off"
        self.counters.add("connect_failed", msg)
        self._set_state(False, msg)

    def _on_disconnect(self, client: mqtt.Client, userdata: object, flags: object, reason: object, props: object) -> None:
        if self._closed or self._refused:  # the refusal already says what happened
            return
        msg = f"lost connection to broker {self.config.url} ({reason}); reconnecting with back-off"
        self.counters.add("disconnects", msg)
        self._set_state(False, msg)

    def _on_message(self, client: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        if self._handler is None:
            return
        try:
            self._handler(message.topic, message.payload, self._clock())  # type: ignore[arg-type]  # paho gives bytes (bytearray only when built by hand)
        except Exception as exc:  # noqa: BLE001 - a bad message must not kill the network thread
            self.counters.add("handler_errors", f"message on {message.topic!r} could not be handled: {exc!r}")

"""Broker connection settings and the topic layout of the GRITSBot X wire format.

Topics (REFERENCE.md §9; a configurable ``prefix`` is put in front of each, so
several testbeds can share one lab broker):

* ``matlab_api/<id>`` — console → robot, one command per control tick;
* ``<id>/status`` — robot → anyone, ``{"batt_volt", "charge_status", …}``;
* ``overhead_tracker/all_robot_pose_data`` — tracker (or simulated fleet) → console.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from urllib.parse import unquote, urlsplit

from swarmdeck.core.checks import in_range

COMMAND_ROOT = "matlab_api"
POSE_TOPIC = "overhead_tracker/all_robot_pose_data"
STATUS_LEAF = "status"


@dataclass(frozen=True)
class MqttConfig:
    """How to reach the broker and which topics and QoS to use.

    Attributes:
        host, port: broker address (1883 plain, 8883 TLS by convention).
        prefix: put in front of every topic (e.g. ``"lab2/"``); "" for the Robotarium layout.
        qos: MQTT QoS for commands, status and poses (0, as vizier, or 1).
        protocol: ``"3.1.1"`` or ``"5"``.
        keepalive: s; the broker drops a silent client after 1.5 × this (vizier uses 5 s).
        tls: connect with TLS; ``ca_certs``/``certfile``/``keyfile`` optional paths.
        username, password: credentials for a shared broker (None: anonymous).
        client_id: "" lets the broker pick one.
        reconnect_min, reconnect_max: back-off between reconnection attempts, s
            (doubling from min to max, reset after a successful connection).
    """

    host: str = "127.0.0.1"
    port: int = 1883
    prefix: str = ""
    qos: int = 0
    protocol: str = "3.1.1"
    keepalive: int = 5
    tls: bool = False
    ca_certs: str | None = None
    certfile: str | None = None
    keyfile: str | None = None
    username: str | None = None
    password: str | None = field(default=None, repr=False)  # never in logs, status lines or recordings
    client_id: str = ""
    reconnect_min: float = 0.1
    reconnect_max: float = 2.0

    def __post_init__(self) -> None:
        if not self.host:
            raise ValueError("MqttConfig.host must not be empty")
        if not in_range(self.port, 1, 65535, integer=True):
            raise ValueError(f"MqttConfig.port must be an integer in 1..65535, got {self.port!r}")
        if self.qos not in (0, 1):
            raise ValueError(f"MqttConfig.qos must be 0 or 1 (QoS 2 only adds latency to a stream), got {self.qos!r}")
        if self.protocol not in ("3.1.1", "5"):
            raise ValueError(f"MqttConfig.protocol must be '3.1.1' or '5', got {self.protocol!r}")
        if any(c in self.prefix for c in "+#"):
            raise ValueError(f"MqttConfig.prefix must not contain MQTT wildcards + or #, got {self.prefix!r}")
        if not in_range(self.keepalive, 1, 3600):
            raise ValueError(f"MqttConfig.keepalive must be 1..3600 s, got {self.keepalive!r}")
        if not (in_range(self.reconnect_min, 0.0, lo_open=True) and in_range(self.reconnect_max, self.reconnect_min)):
            raise ValueError(
                f"MqttConfig needs 0 < reconnect_min <= reconnect_max, got {self.reconnect_min!r}, {self.reconnect_max!r}"
            )

    # ---------------------------------------------------------------- topics
    def command_topic(self, robot_id: int) -> str:
        return f"{self.prefix}{COMMAND_ROOT}/{int(robot_id)}"

    @property
    def command_wildcard(self) -> str:
        return f"{self.prefix}{COMMAND_ROOT}/+"

    @property
    def pose_topic(self) -> str:
        return f"{self.prefix}{POSE_TOPIC}"

    def status_topic(self, robot_id: int) -> str:
        return f"{self.prefix}{int(robot_id)}/{STATUS_LEAF}"

    @property
    def status_wildcard(self) -> str:
        return f"{self.prefix}+/{STATUS_LEAF}"

    def robot_id_of_command_topic(self, topic: str) -> int | None:
        """The id in ``<prefix>matlab_api/<id>``, or None for any other topic."""
        head = f"{self.prefix}{COMMAND_ROOT}/"
        return _small_int(topic[len(head):]) if topic.startswith(head) else None

    def robot_id_of_status_topic(self, topic: str) -> int | None:
        """The id in ``<prefix><id>/status``, or None for any other topic."""
        tail = f"/{STATUS_LEAF}"
        if not (topic.startswith(self.prefix) and topic.endswith(tail)):
            return None
        return _small_int(topic[len(self.prefix): -len(tail)])

    @property
    def url(self) -> str:
        scheme = "mqtts" if self.tls else "mqtt"
        return f"{scheme}://{self.host}:{self.port}"

    def with_client_id(self, client_id: str) -> MqttConfig:
        return replace(self, client_id=client_id)


def _small_int(text: str) -> int | None:
    if not (text.isascii() and text.isdigit()) or len(text) > 9:
        return None
    return int(text)


def redact_url(url: str) -> str:
    """``url`` with any password replaced by ``***`` (for messages, status lines and recordings)."""
    text = str(url)
    scheme, sep, rest = text.partition("://")
    if not sep:
        return text
    auth, at, host = rest.rpartition("@")
    if not at or ":" not in auth.split("/")[0]:
        return text
    user = auth.split(":", 1)[0]
    return f"{scheme}://{user}:***@{host}"


def parse_broker_url(url: str, **overrides: object) -> MqttConfig:
    """``mqtt://[user[:password]@]host[:port][/prefix/]`` → :class:`MqttConfig`.

    ``mqtts://`` turns TLS on (default port 8883). A path becomes the topic
    prefix (``mqtt://lab:1883/arena2/`` → prefix ``"arena2/"``). Keyword
    overrides set any other field (qos, protocol, ca_certs, …).

    Raises:
        ValueError: the URL is not of that form (the message says what is expected).
    """
    expected = "expected mqtt://HOST:PORT or mqtts://HOST:PORT (optionally user:password@ and /prefix/)"
    shown = redact_url(url)
    try:
        parts = urlsplit(url)
        port = parts.port
    except ValueError as exc:
        raise ValueError(f"bad broker URL {shown!r}: {exc}; {expected}") from None
    if parts.scheme not in ("mqtt", "mqtts", "tcp", "ssl"):
        raise ValueError(f"bad broker URL {shown!r}: scheme {parts.scheme!r} is not supported; {expected}")
    if not parts.hostname:
        raise ValueError(f"bad broker URL {shown!r}: no host; {expected}")
    tls = parts.scheme in ("mqtts", "ssl")
    prefix = parts.path.strip("/")
    fields: dict[str, object] = {
        "host": parts.hostname,
        "port": port if port is not None else (8883 if tls else 1883),
        "tls": tls,
        "prefix": f"{prefix}/" if prefix else "",
        "username": unquote(parts.username) if parts.username else None,
        "password": unquote(parts.password) if parts.password else None,
    }
    fields.update({k: v for k, v in overrides.items() if v is not None})
    return MqttConfig(**fields)  # type: ignore[arg-type]

"""A real mosquitto broker for the MQTT tests: free loopback port, generated config, torn down after.

The fixture ``mosquitto`` is registered for every test by ``pytest_plugins`` in ``tests/conftest.py``.
The broker listens on 127.0.0.1 only, allows anonymous clients and keeps no
persistence. :meth:`Broker.kill` and :meth:`Broker.start` let a test take it
down and bring it back on the same port.
"""
from __future__ import annotations

import getpass
import os
import shutil
import socket
import subprocess
import time
from pathlib import Path

import pytest

MOSQUITTO = shutil.which("mosquitto") or "/usr/sbin/mosquitto"


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Broker:
    """One mosquitto process on ``127.0.0.1:port``."""

    def __init__(self, workdir: Path, port: int | None = None, listener_conf: str = "allow_anonymous true\n") -> None:
        self.port = port or free_port()
        self.workdir = workdir
        self.conf = workdir / "mosquitto.conf"
        self.log = workdir / "mosquitto.log"
        self.conf.write_text(
            f"listener {self.port} 127.0.0.1\n"
            + listener_conf
            + f"user {getpass.getuser()}\n"  # as root, mosquitto would switch to 'mosquitto' and lose our files
            + "persistence false\n"
            f"log_dest file {self.log}\n"
            "log_type error\nlog_type warning\nlog_type notice\n"
            "max_queued_messages 10000\n"
        )
        self.proc: subprocess.Popen | None = None

    @property
    def url(self) -> str:
        return f"mqtt://127.0.0.1:{self.port}"

    def start(self, timeout: float = 10.0) -> None:
        """Start mosquitto and wait (polling, with a deadline) until it accepts connections."""
        self.proc = subprocess.Popen([MOSQUITTO, "-c", str(self.conf)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                err = self.proc.stderr.read().decode(errors="replace") if self.proc.stderr else ""
                raise RuntimeError(f"mosquitto exited with {self.proc.returncode}: {err} {self._log_text()}")
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.2):
                    return
            except OSError:
                time.sleep(0.02)
        raise RuntimeError(f"mosquitto did not accept connections on port {self.port} within {timeout} s")

    def kill(self) -> None:
        """Kill the broker at once (SIGKILL), as a crash or a pulled cable would."""
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=5)
        self.proc = None

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=5)
        self.proc = None

    def _log_text(self) -> str:
        return self.log.read_text(errors="replace") if self.log.exists() else ""


@pytest.fixture
def mosquitto(tmp_path: Path):
    """A running broker (``Broker``); killed after the test."""
    if not (os.path.exists(MOSQUITTO) and os.access(MOSQUITTO, os.X_OK)):
        pytest.skip("Debian's mosquitto is not installed (scripts/test installs it)")
    broker = Broker(tmp_path)
    broker.start()
    try:
        yield broker
    finally:
        broker.stop()


class Collector:
    """A raw paho client (no swarmdeck code) that records every message on ``topics`` of a broker."""

    def __init__(self, broker: Broker, topics: list[str]) -> None:
        import threading

        import paho.mqtt.client as mqtt
        from paho.mqtt.enums import CallbackAPIVersion

        self.messages: list[tuple[str, bytes]] = []
        self._lock = threading.Lock()
        self._ready = threading.Event()
        self.client = mqtt.Client(CallbackAPIVersion.VERSION2)

        def on_connect(client, userdata, flags, reason, props):
            for t in topics:
                client.subscribe(t)

        def on_message(client, userdata, msg):
            with self._lock:
                self.messages.append((msg.topic, msg.payload))

        acks = []

        def on_subscribe(client, userdata, mid, reasons, props):
            acks.append(mid)
            if len(acks) == len(topics):  # every subscription is active at the broker
                self._ready.set()

        self.client.on_connect = on_connect
        self.client.on_message = on_message
        self.client.on_subscribe = on_subscribe
        self.client.connect("127.0.0.1", broker.port)
        self.client.loop_start()
        if not self._ready.wait(10):
            raise RuntimeError("collector could not subscribe")

    def publish(self, topic: str, payload: bytes) -> None:
        self.client.publish(topic, payload).wait_for_publish(5)

    def wait_for(self, predicate, timeout: float = 60.0) -> list[tuple[str, bytes]]:
        """Poll (with a deadline) until ``predicate(messages)`` is true; returns the messages."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self._lock:
                msgs = list(self.messages)
            if predicate(msgs):
                return msgs
            time.sleep(0.01)
        with self._lock:
            raise AssertionError(f"condition not met within {timeout} s; got {len(self.messages)} messages: "
                                 f"{self.messages[-5:]}")

    def close(self) -> None:
        self.client.disconnect()
        self.client.loop_stop()


def wait_until(predicate, timeout: float = 60.0, what: str = "condition"):
    """Poll ``predicate()`` until it returns something truthy (returned) or fail after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"{what} not reached within {timeout} s")
        time.sleep(0.01)

"""Live Foxglove: a WebSocket client speaking the Foxglove protocol subscribes to the bridge and receives one
SceneUpdate per tick; `swarmdeck console --foxglove` serves it, and refuses a port in use in one line."""
from __future__ import annotations

import asyncio
import base64
import json
import os
import signal
import socket
import struct
import subprocess
import sys

import numpy as np
import websockets
from foxglove_schemas import decode

from swarmdeck.console.cli import main as cli
from swarmdeck.console.recording.foxglove import TOPIC_LOG, TOPIC_ROBOTS
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.foxglove_live import FoxgloveBridge

SUBPROTOCOL = "foxglove.sdk.v1"


class Client:
    """A minimal Foxglove WebSocket client: serverInfo, advertise, subscribe, binary message data (opcode 1)."""

    def __init__(self, ws):
        self.ws = ws
        self.channels: dict[str, dict] = {}
        self.subs: dict[int, dict] = {}

    @classmethod
    async def connect(cls, url: str) -> Client:
        c = cls(await websockets.connect(url, subprotocols=[SUBPROTOCOL]))
        assert c.ws.subprotocol == SUBPROTOCOL
        while len(c.channels) < 10:  # every channel is advertised at connection
            msg = json.loads(await asyncio.wait_for(c.ws.recv(), 10))
            if msg["op"] == "advertise":
                c.channels.update({ch["topic"]: ch for ch in msg["channels"]})
        return c

    async def subscribe(self, *topics: str) -> None:
        subs = [{"id": i + 1, "channelId": self.channels[t]["id"]} for i, t in enumerate(topics)]
        self.subs.update({s["id"]: self.channels[t] for s, t in zip(subs, topics)})
        await self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))

    async def message(self, timeout: float = 10.0):  # noqa: ASYNC109
        """(channel, log time ns, payload) of the next message data."""
        while True:
            data = await asyncio.wait_for(self.ws.recv(), timeout)
            if isinstance(data, bytes) and data[0] == 0x01:
                sub, ns = struct.unpack_from("<IQ", data, 1)
                return self.subs[sub], ns, data[13:]


def _decode(channel, payload):
    """Decode with the schema the server advertised (protobuf: a base64 FileDescriptorSet)."""
    return decode(channel["schemaName"], base64.b64decode(channel["schema"]), payload)


def test_bridge_sends_a_scene_update_per_tick():
    loop = ControlLoop(LoopConfig(n_robots=6, seed=3))
    bridge = FoxgloveBridge(loop.config.bounds, port=0)
    loop.subscribe(bridge.offer)

    async def run():
        c = await Client.connect(bridge.url)
        assert c.channels[TOPIC_ROBOTS]["schemaName"] == "foxglove.SceneUpdate"
        await c.subscribe(TOPIC_ROBOTS)
        for _ in range(100):  # until the server has the subscription (it is asynchronous)
            loop.tick()
            bridge.send_pending()
            try:
                await c.message(timeout=0.3)
                break
            except TimeoutError:
                continue
        got = []
        for _ in range(5):
            frame = loop.tick()
            bridge.send_pending()
            ch, ns, payload = await c.message()
            upd = _decode(ch, payload)
            robots = next(e for e in upd.entities if e.id == "robots")
            xy = np.array([[cyl.pose.position.x, cyl.pose.position.y] for cyl in robots.cylinders])
            assert np.allclose(xy, frame.poses[:, :2])
            got.append(ns)
        await c.ws.close()
        return got

    try:
        times = asyncio.run(run())
    finally:
        bridge.close()
    assert times == sorted(times) and len(set(times)) == 5  # one SceneUpdate per tick, in order
    assert bridge.errors == 0


def test_events_of_skipped_frames_still_reach_the_log():
    loop = ControlLoop(LoopConfig(n_robots=3, seed=1))
    bridge = FoxgloveBridge(loop.config.bounds, port=0)
    loop.subscribe(bridge.offer)

    async def run():
        c = await Client.connect(bridge.url)
        await c.subscribe(TOPIC_LOG)
        texts = []
        for k in range(100):
            loop.post(f"note {k}")
            loop.tick()
            loop.post(f"note {k}b")
            loop.tick()
            bridge.send_pending()  # two frames pending: the first is skipped, its event is still sent
            try:
                while True:
                    ch, _, payload = await c.message(timeout=0.3)
                    texts.append(_decode(ch, payload).message)
            except TimeoutError:
                pass
            if texts:
                break
        await c.ws.close()
        return k, texts

    try:
        k, texts = asyncio.run(run())
    finally:
        bridge.close()
    assert texts == [f"note {k}", f"note {k}b"] and bridge.skipped >= 1


def _busy_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen()
    return s


def test_console_refuses_a_foxglove_port_in_use(capsys):
    s = _busy_port()
    port = s.getsockname()[1]
    try:
        code = cli(["console", "--foxglove", str(port), "--port", "0", "--no-record", "--no-inputs", "--robots", "3",
                    "--duration", "1"])
    finally:
        s.close()
    err = capsys.readouterr().err.strip()
    assert code == 2 and f"Foxglove port {port}" in err and "in use" in err and "\n" not in err


def test_swarmdeck_console_foxglove_serves_live(tmp_path):
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    exe = os.path.join(os.path.dirname(sys.executable), "swarmdeck")
    proc = subprocess.Popen([exe, "console", "--foxglove", "0", "--port", "0",
                             "--no-record", "--no-inputs", "--robots", "4", "--duration", "120"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path)
    try:
        url = None
        for line in proc.stdout:
            if "Foxglove live at " in line:
                url = line.split("Foxglove live at ")[1].split()[0]
                break
        assert url and url.startswith("ws://127.0.0.1:")

        async def run():
            c = await Client.connect(url)
            await c.subscribe(TOPIC_ROBOTS)
            out = []
            for _ in range(3):
                ch, ns, payload = await c.message(timeout=30)
                out.append((ns, len(next(e for e in _decode(ch, payload).entities if e.id == "robots").cylinders)))
            await c.ws.close()
            return out

        got = asyncio.run(run())
        assert [n for _, n in got] == [4, 4, 4] and got[0][0] < got[1][0] < got[2][0]
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)

"""The live bridge (`--foxglove`) serves the official Foxglove WebSocket client, `@foxglove/ws-protocol`
from npm (run by node, tests/js/), whichever name of the protocol it asks for: `foxglove.websocket.v1`
(the client's own) and `foxglove.sdk.v1` (the SDK's); a client asking for neither is refused.
`bash scripts/test` installs node and the client (`npm ci` in tests/js)."""
from __future__ import annotations

import asyncio
import base64
import json
import logging
import shutil
import subprocess
import threading
from pathlib import Path

import numpy as np
import pytest
import websockets
from foxglove_schemas import decode

from swarmdeck.console.recording.foxglove import TOPIC_ROBOTS
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.foxglove_live import FoxgloveBridge

JS = Path(__file__).resolve().parents[1] / "js"


@pytest.fixture(scope="module")
def node() -> str:
    exe = shutil.which("node") or shutil.which("nodejs")
    assert exe, "node is not installed: `bash scripts/test` installs it (Debian's nodejs)"
    assert (JS / "node_modules" / "@foxglove" / "ws-protocol").is_dir(), \
        "the official client is not installed: `bash scripts/test` runs `npm ci` in tests/js"
    return exe


@pytest.fixture
def live():
    """A bridge fed by a loop ticking on its own thread until the test ends; yields (bridge, frames)."""
    loop = ControlLoop(LoopConfig(n_robots=5, seed=4))
    bridge = FoxgloveBridge(loop.config.bounds, port=0)
    frames = []
    loop.subscribe(bridge.offer)
    loop.subscribe(frames.append)
    stop = threading.Event()

    def run() -> None:
        while not stop.wait(0.03):
            loop.tick()
            bridge.send_pending()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    yield bridge, frames
    stop.set()
    thread.join(5)
    bridge.close()
    loop.close()


@pytest.mark.parametrize("subprotocol", ["foxglove.websocket.v1", "foxglove.sdk.v1"])
def test_the_official_client_receives_the_robots(node, live, subprotocol):
    bridge, frames = live
    out = subprocess.run([node, str(JS / "foxglove_client.js"), bridge.url, subprotocol, TOPIC_ROBOTS, "3"],
                         capture_output=True, text=True, timeout=90, cwd=JS)
    lines = [json.loads(x) for x in out.stdout.splitlines()]
    assert out.returncode == 0, (out.stdout, out.stderr)
    assert lines[0] == {"event": "open", "protocol": subprotocol}
    assert {"event": "serverInfo", "name": "swarmdeck"} in lines
    channel = next(x for x in lines if x["event"] == "channel")
    assert channel["schemaName"] == "foxglove.SceneUpdate" and channel["encoding"] == "protobuf"
    messages = [x for x in lines if x["event"] == "message"]
    assert len(messages) == 3
    shown = list(frames)
    for m in messages:
        upd = decode(channel["schemaName"], base64.b64decode(channel["schema"]), base64.b64decode(m["data"]))
        robots = next(e for e in upd.entities if e.id == "robots")
        xy = np.array([[c.pose.position.x, c.pose.position.y] for c in robots.cylinders])
        assert any(np.allclose(xy, f.poses[:, :2]) for f in shown)  # the poses of one of the loop's frames
    assert bridge.errors == 0


def test_a_client_asking_for_another_protocol_is_refused(live, caplog):
    bridge, _ = live

    async def attempt():
        with pytest.raises(websockets.exceptions.InvalidStatus) as info:
            await websockets.connect(bridge.url, subprotocols=["mqtt"], proxy=None)
        return info.value.response

    response = asyncio.run(attempt())
    assert response.status_code == 400 and b"foxglove.websocket.v1" in response.body
    assert bridge.relay.refused == 1  # counted, and no traceback logged for it
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING], caplog.records

"""The projector server over real HTTP on loopback: the config before the loop starts, only the newest Frame to
each page (skipped ones counted), settings checked and applied at once, bad requests answered, pages told when
it stops; the console's projector options refuse a calibration that does not fit the arena."""
from __future__ import annotations

import base64
import json
import urllib.error
import urllib.request

import pytest

from swarmdeck.console.cli import main as cli_main
from swarmdeck.console.projector.server import ProjectorServer
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.tracking.projector import ProjectorCalibration, SyntheticProjector


def _get(url: str) -> dict:
    with urllib.request.urlopen(url, timeout=30) as r:
        return json.loads(r.read())


@pytest.fixture
def served():
    loop = ControlLoop(LoopConfig(n_robots=6, seed=2))
    proj = SyntheticProjector()
    srv = ProjectorServer(loop.config.bounds, ProjectorCalibration(proj.homography(), proj.size, DEFAULT_BOUNDS),
                          port=0).start()
    loop.subscribe(srv.offer)
    base = srv.url.rsplit("/", 1)[0] + "/projector"
    try:
        yield loop, srv, base
    finally:
        srv.close()
        loop.close()


def test_config_before_the_loop_starts_then_only_the_newest_frame(served):
    loop, srv, base = served
    first = _get(f"{base}/next?seq=0&version=-1")
    assert first["frame"] is None and first["config"]["H"] is not None and first["config"]["size"] == [1280, 800]
    version = first["config"]["version"]
    for _ in range(5):
        loop.tick()
    got = _get(f"{base}/next?seq=0&version={version}")
    assert got["config"] is None and got["frame"]["seq"] == 5 and got["frame"]["n"] == 6
    d = got["frame"]["density"]
    assert len(base64.b64decode(d["rgb"])) == 3 * d["w"] * d["h"] > 0
    loop.tick()
    loop.tick()
    again = _get(f"{base}/next?seq=5&version={version}")
    assert again["frame"]["seq"] == 7
    assert srv.state()["skipped"] == 1  # frame 6 was never sent: newest only


def test_settings_apply_at_once_and_bad_ones_are_refused(served):
    loop, srv, base = served
    loop.tick()
    v0 = _get(f"{base}/next?seq=0&version=-1")["config"]["version"]
    srv.set(blackout=True)
    got = _get(f"{base}/next?seq=1&version={v0}")  # no new Frame: the new settings alone answer, with the Frame
    assert got["config"]["settings"]["blackout"] is True
    assert got["frame"]["seq"] == 1 and got["frame"]["density"] is None and got["frame"]["halos"] is None
    with pytest.raises(ValueError, match="opacity"):
        srv.set(opacity=2.0)
    with pytest.raises(TypeError):
        srv.set(colour="red")
    assert srv.settings.blackout is True and srv.settings.opacity == 1.0


def test_bad_requests_and_a_stopped_server(served):
    loop, srv, base = served
    with pytest.raises(urllib.error.HTTPError) as exc:
        urllib.request.urlopen(f"{base}/next?seq=abc", timeout=30)
    assert exc.value.code == 400
    with pytest.raises(urllib.error.HTTPError) as exc:
        urllib.request.urlopen(f"{base}/nothing-here", timeout=30)
    assert exc.value.code == 404
    with urllib.request.urlopen(base, timeout=30) as r:
        assert b"projector.js" in r.read()
    srv.close()
    with pytest.raises(urllib.error.URLError):
        urllib.request.urlopen(f"{base}/next?seq=0&version=-1", timeout=30)


def test_console_refuses_a_projector_calibration_it_cannot_use(tmp_path, capsys):
    proj = SyntheticProjector()
    path = tmp_path / "projector.json"
    ProjectorCalibration(proj.homography(), proj.size, DEFAULT_BOUNDS).save(path)
    assert cli_main(["console", "--projector-calibration", str(path), "--duration", "1", "--no-record"]) != 0
    assert "needs --projector" in capsys.readouterr().err
    # the 3.2 × 2 m calibration on a 40 × 30 m arena: most of the arena lies off the projector's image
    assert cli_main(["console", "--projector", "0", "--projector-calibration", str(path), "--arena", "40x30",
                     "--robots", "2", "--duration", "1", "--no-record", "--port", "0", "--no-inputs"]) != 0
    assert "off the projector image" in capsys.readouterr().err
    path.write_text("[1, 2]")
    assert cli_main(["console", "--projector", "0", "--projector-calibration", str(path), "--duration", "1",
                     "--no-record", "--port", "0", "--no-inputs"]) != 0
    assert "must hold a JSON object" in capsys.readouterr().err


def test_the_event_stream_sends_the_config_then_the_newest_frame(served):
    loop, srv, base = served
    loop.tick()
    loop.tick()
    with urllib.request.urlopen(f"{base}/stream", timeout=30) as r:
        assert r.headers["Content-Type"] == "text/event-stream"
        events: list[tuple[str, dict]] = []
        name = None
        while len(events) < 2:
            line = r.readline().decode().rstrip("\n")
            if line.startswith("event: "):
                name = line[7:]
            elif line.startswith("data: "):
                events.append((name or "", json.loads(line[6:])))
    assert events[0][0] == "config" and events[0][1]["size"] == [1280, 800]
    assert events[1][0] == "frame" and events[1][1]["seq"] == 2


def test_a_page_that_knew_a_restarted_server_starts_again(served):
    loop, srv, base = served
    loop.tick()
    got = _get(f"{base}/next?seq=0&version=-1")
    assert got["config"]["instance"] == srv.feed.instance and got["frame"]["seq"] == 1
    # a page that had seen frame 57 of an earlier server: answered as a new page, not left waiting for frame 58
    again = _get(f"{base}/next?seq=57&version=0&instance=0123456789ab")
    assert again["config"]["instance"] == srv.feed.instance and again["frame"]["seq"] == 1

"""Crashed recordings and the ``mcap`` package's own readers: non-seeking reading before, ``swarmdeck recover``
after a real ``kill -9``; bad input to ``recover`` is one line, exit 2, and the input is never touched."""
from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import textwrap
from collections import Counter

import pytest
from mcap.exceptions import EndOfFile
from mcap.reader import NonSeekingReader, make_reader

from swarmdeck.console.cli import main as cli
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.schemas import TOPIC_FRAME

CHILD = textwrap.dedent("""
    import sys, time
    from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
    from recording_synth import retimed, simulated_frames

    frames = list(simulated_frames(n_robots=12, n_ticks=40, dt=0.02))
    rec = Recorder(sys.argv[1], {"config": {"child": True}}, RecorderConfig(flush_interval=0.1))
    k = 0
    while True:                               # a 50 Hz loop that records every tick, until killed
        now = time.monotonic()
        rec.write_frame(retimed(frames[k % len(frames)], k, now))
        rec.write_datagram(b"ping", ("127.0.0.1", 9), "udp", now)
        if k % 10 == 0:
            rec.write_event(now, "operator", f"note {k}")
        print(k, rec.status().bytes_written, flush=True)
        k += 1
        time.sleep(0.02)
""")


def _digest(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def crashed(tmp_path_factory):
    """A recording whose writer was killed with SIGKILL after it had written several chunks."""
    path = tmp_path_factory.mktemp("crash") / "crash.mcap"
    env = {**os.environ, "PYTHONPATH": os.path.dirname(os.path.dirname(os.path.abspath(__file__)))}
    proc = subprocess.Popen([sys.executable, "-c", CHILD, str(path)], stdout=subprocess.PIPE, text=True, env=env)
    try:
        sizes = set()
        for line in proc.stdout:
            k, size = map(int, line.split())
            sizes.add(size)
            if k >= 30 and len(sizes) >= 4:  # the header and at least three chunk flushes are in the file
                break
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert proc.returncode == -signal.SIGKILL
    return path


def _swarmdeck_view(path):
    with open_recording(path) as r:
        return r.message_counts(), [t for t, _ in r.frames()], r.rel, r.indexed


def test_non_seeking_reader_reads_every_frame_of_a_killed_file(crashed):
    counts, times, rel, indexed = _swarmdeck_view(crashed)
    assert not indexed and counts[TOPIC_FRAME] >= 1
    with open(crashed, "rb") as f:
        with pytest.raises(EndOfFile):  # the mcap package's documented behaviour at a truncation
            got = []
            for _, channel, msg in NonSeekingReader(f).iter_messages(log_time_order=False):
                got.append((channel.topic, msg.log_time))
    assert Counter(t for t, _ in got) == Counter(counts)
    assert [rel(ns) for topic, ns in got if topic == TOPIC_FRAME] == times
    with open(crashed, "rb") as f, pytest.raises(Exception):  # noqa: B017  (whatever mcap raises on a missing summary)
        make_reader(f).get_summary()  # what recover is for: the seeking reader needs the summary


def test_recover_gives_a_file_make_reader_reads_completely(crashed, tmp_path, capsys):
    before = _digest(crashed)
    counts, times, _, _ = _swarmdeck_view(crashed)
    out = tmp_path / "fixed.mcap"
    assert cli(["recover", str(crashed), "-o", str(out)]) == 0
    assert "cut off" in capsys.readouterr().err
    assert _digest(crashed) == before, "recover never modifies its input"
    with open(out, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.chunk_indexes
        got = [(channel.topic, msg.log_time) for _, channel, msg in reader.iter_messages()]
        assert summary.statistics.message_count == len(got)
        last = max(ns for topic, ns in got if topic == TOPIC_FRAME)
        assert sum(1 for _ in reader.iter_messages(topics=[TOPIC_FRAME], starting_at=last)) == 1  # seeks by time
    assert Counter(t for t, _ in got) == Counter(counts)
    r_counts, r_times, rel, indexed = _swarmdeck_view(out)
    assert indexed and r_counts == counts and r_times == times
    with open_recording(out) as r:
        assert r.config()["config"] == {"child": True}
        assert r.metadata.get("recording_format") is not None
        assert r.n_chunks >= 3  # chunk boundaries kept: seeking stays cheap


def test_recover_default_output_and_clean_input(crashed, tmp_path, capsys):
    src = tmp_path / "run.mcap"
    src.write_bytes(crashed.read_bytes())
    assert cli(["recover", str(src)]) == 0
    first = tmp_path / "run.recovered.mcap"
    assert capsys.readouterr().out.strip() == str(first)
    # recovering a clean file copies it whole
    again = tmp_path / "again.mcap"
    assert cli(["recover", str(first), "-o", str(again)]) == 0
    assert "closed cleanly" in capsys.readouterr().err
    assert _swarmdeck_view(again)[:2] == _swarmdeck_view(first)[:2]


@pytest.mark.parametrize("content, reason", [
    (b"", "is empty"),
    (b"this is a text file, not a recording\n", "not an MCAP file"),
    (bytes([137, 77, 67, 65, 80, 48, 13, 10, 1, 40, 0]), "cut off inside the MCAP header"),
    (bytes([137, 77, 67]), "cut off inside the MCAP magic"),
])
def test_recover_refuses_bad_input_in_one_line(tmp_path, capsys, content, reason):
    src = tmp_path / "bad.mcap"
    src.write_bytes(content)
    out = tmp_path / "out.mcap"
    assert cli(["recover", str(src), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert reason in err and str(src) in err and "\n" not in err
    assert src.read_bytes() == content and not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["bad.mcap"], "no temporary file left behind"


def test_recover_refuses_to_overwrite_its_input(crashed, capsys):
    before = _digest(crashed)
    assert cli(["recover", str(crashed), "-o", str(crashed)]) == 2
    assert "never overwrites" in capsys.readouterr().err
    assert _digest(crashed) == before

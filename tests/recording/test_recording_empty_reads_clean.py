"""A recording closed cleanly before its first frame (a console stopped while starting) reads as cleanly
closed: its summary has no chunk index because there are no chunks, and the reader used to take that for an
unreadable summary ("recovered by scanning")."""
from __future__ import annotations

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig


def test_a_cleanly_closed_empty_recording_reads_without_a_warning(tmp_path) -> None:
    path = tmp_path / "empty.mcap"
    status = Recorder(path, {"note": "closed before its first frame"}, RecorderConfig()).close()
    assert "recorded 0 frames" in status.message
    with open_recording(path) as r:
        assert r.indexed and r.warnings == [], r.warnings
        assert r.last_frame is None and r.metadata["note"] == "closed before its first frame"

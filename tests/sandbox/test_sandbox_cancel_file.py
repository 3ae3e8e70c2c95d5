"""The cancel file of a batch of runs (console/sandbox/cancel_file.py, shared by verification and sweeps): set the
caller's event and the file appears (the watcher touches it, or the check does at once); the folder goes at the end."""
from __future__ import annotations

import os
import threading
import time
from pathlib import Path

from swarmdeck.console.sandbox.cancel_file import CancelSeen, cancel_file


def test_the_watcher_touches_the_file_once_the_event_is_set_and_the_folder_goes_at_the_end() -> None:
    event = threading.Event()
    with cancel_file(event, "test-cancel") as (path, cancelled):
        assert not os.path.exists(path) and not cancelled()
        event.set()
        deadline = time.monotonic() + 60
        while not os.path.exists(path):  # the watcher's doing (every 0.1 s), without calling cancelled()
            assert time.monotonic() < deadline, "the watcher never touched the cancel file"
            time.sleep(0.02)
        assert cancelled()
    assert not Path(path).parent.exists()


def test_without_an_event_nothing_is_cancelled() -> None:
    with cancel_file(None, "test-cancel") as (path, cancelled):
        assert not cancelled() and not os.path.exists(path)
    assert not Path(path).parent.exists()


def test_a_run_looks_for_the_file_at_most_once_a_period_and_keeps_what_it_saw(tmp_path) -> None:
    path = tmp_path / "cancel"
    hourly = CancelSeen(str(path), period=3600.0)
    assert not hourly()  # the first call looks
    path.touch()
    assert not hourly(), "looked again within its period (a stat every tick)"
    every_call = CancelSeen(str(path), period=0.0)
    assert every_call()
    path.unlink()
    assert every_call(), "a cancel seen stays seen"

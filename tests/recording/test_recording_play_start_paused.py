"""``swarmdeck play --start S --paused`` opens showing the frame at S (it used to show the first frame: the seek
was never drawn, the paused playback thread draws only when something changes) — one recording and several."""
from __future__ import annotations

import pytest
from compare_synth import straight_run

from swarmdeck.console.cli import build_parser
from swarmdeck.console.cli.play import open_player


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("start")
    return straight_run(d / "a.mcap", 65), straight_run(d / "b.mcap", 49)


@pytest.mark.parametrize("several", [False, True], ids=["one", "two"])
def test_paused_at_start_shows_that_frame(files, several):
    names = list(files) if several else [files[0]]
    args = build_parser().parse_args(["play", *names, "--port", "0", "--start", "2.5", "--paused"])
    app, runs = open_player(args)
    try:
        assert not app.player.playing and app.player.frame.tick == 40  # 2.5 s at 1/16 s a frame
        assert app.slider.value == 2.5
        assert "tick 40" in app.status.content
        if not several:
            assert app.scene.nodes.robots.batched_positions[1, 0] == pytest.approx(0.5 - 0.2 * 2.5)
    finally:
        app.close()
        for r in runs:
            r.close()

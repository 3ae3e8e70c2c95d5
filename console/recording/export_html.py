"""Standalone HTML replay of a recording through viser's scene serializer (REFERENCE.md §8).

The console's own :class:`~swarmdeck.console.web.scene.ArenaScene` draws the frames
into a private viser server whose scene messages are captured by
``server.get_scene_serializer()``; frames are sampled at ``fps`` and separated
by ``insert_sleep`` of their recorded spacing, so the HTML file (viser's
client with the data embedded, no server needed) replays at real time with
viser's own play/pause/timeline bar.
"""
from __future__ import annotations

import os
from pathlib import Path

from swarmdeck.console.recording.reader import Recording


def export_html(recording: Recording, out: str | os.PathLike[str], fps: float = 10.0,
                start: float | None = None, end: float | None = None, dark_mode: bool = False) -> tuple[Path, int]:
    """Write the replay of frames in [start, end) s sampled at ``fps`` Hz to ``out``; returns (path, frames drawn)."""
    import contextlib
    import io

    import viser

    from swarmdeck.console.web.scene import ArenaScene, SceneStyle

    if not (fps > 0):
        raise ValueError(f"fps must be > 0, got {fps!r}")
    first = recording.first_frame
    if first is None:
        raise ValueError(f"{recording.path} holds no readable frame")
    # a private server only feeds the serializer: its "HTTP … Websocket …" box (printed whatever
    # verbose says) would look like something to open
    with contextlib.redirect_stdout(io.StringIO()):
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        serializer = server.get_scene_serializer()
        # the replay has no control panel: the arena in the middle of the page
        scene = ArenaScene(server, bounds=first.bounds, style=SceneStyle(panel_shift=0.0))
        period = 1.0 / fps
        last_t: float | None = None
        next_t = -float("inf")
        drawn = 0
        for t, frame in recording.frames(start, end):
            if t < next_t - 1e-9:
                continue
            next_t = next_t + period if last_t is not None and next_t + period > t else t + period
            if last_t is not None:
                serializer.insert_sleep(t - last_t)
            scene.draw(frame)
            last_t = t
            drawn += 1
        html = serializer.as_html(dark_mode=dark_mode)
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(html, encoding="utf-8")
    return path, drawn

"""Playback of recorded sessions: the timeline logic and the viser player.

:class:`Player` is the timeline with no I/O: a position in recording time
(s since the first frame), play/pause, step, rate 0.1×–4×, loop and an A/B
range, advanced by :meth:`Player.update` from any clock (virtual in tests).
It reads frames from a :class:`~swarmdeck.console.recording.reader.Recording`
(seeking through the chunk index, so long files seek as fast as short ones).

:class:`PlayerApp` shows a recording in the browser: the console's own
:class:`~swarmdeck.console.web.scene.ArenaScene` draws every Frame (live and
playback differ only in where Frames come from), with a timeline panel
(slider, play/pause, step, rate, loop, A/B), the layer toggles and plots of
the frames shown. ``swarmdeck play FILE`` runs it.
"""
from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from swarmdeck.console.recording.reader import Recording
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.service_thread import ServiceThread

if TYPE_CHECKING:
    import viser

RATE_MIN, RATE_MAX = 0.1, 4.0
RATES: tuple[float, ...] = (0.1, 0.25, 0.5, 1.0, 2.0, 4.0)
PLOT_BACKFILL = 5.0  # s of recording shown in the plots after a seek
SLIDER_STEP = 0.01  # s: the timeline slider's precision
MAX_EVENTS = 500  # events (repeats collapsed) the player lists …
MAX_MARKS = 100  # … marks on the timeline …
MAX_LISTED = 30  # … and lists in the panel's text


class Player:
    """Timeline over a recording (no I/O). Times are recording time, s.

    Args:
        recording: an open recording with at least one frame.
        clock: monotonic seconds used by :meth:`update` when ``now`` is omitted.
    """

    def __init__(self, recording: Recording | Sequence[Recording], clock: Callable[[], float] = time.monotonic,
                 offsets: Sequence[float] | None = None) -> None:
        recordings = [recording] if isinstance(recording, Recording) else list(recording)
        if not recordings:
            raise ValueError("the player needs at least one recording")
        for r in recordings:
            if r.empty:
                raise ValueError(f"{r.path} holds no readable frame")
        offs = tuple(0.0 for _ in recordings) if offsets is None else tuple(float(o) for o in offsets)
        if len(offs) != len(recordings) or not all(math.isfinite(o) and o >= 0 for o in offs):
            raise ValueError(f"one finite offset >= 0 s per recording expected, got {offsets!r}")
        self.recording = recordings[0]
        self.recordings: tuple[Recording, ...] = tuple(recordings)
        self.offsets: tuple[float, ...] = offs  # timeline time of each run's first frame, s
        self.duration = max(o + r.duration for o, r in zip(offs, recordings))
        self._clock = clock
        self._lock = threading.RLock()
        self._pos = 0.0
        self._shown: list[tuple[float, Frame]] = []
        for r in recordings:  # each run's frame at timeline 0 (before its offset: its first)
            first = r.first_frame
            assert first is not None
            self._shown.append((0.0, first))
        self._frame_t, self._frame = 0.0, self._shown[0][1]
        self.playing = False
        self.rate = 1.0
        self.loop = False
        self.a: float | None = None
        self.b: float | None = None
        self._last: float | None = None
        self.version = 0  # bumps whenever a shown frame changes

    # ------------------------------------------------------------------ state
    @property
    def position(self) -> float:
        """Playback position, s since the first frame."""
        return self._pos

    @property
    def frame(self) -> Frame:
        """The frame shown at the position (the last frame at or before it; with several runs, run A's)."""
        return self._frame

    @property
    def frame_time(self) -> float:
        """Timeline time of the latest frame shown, s (one run: the recording time of :attr:`frame`)."""
        return self._frame_t

    @property
    def frames(self) -> tuple[Frame, ...]:
        """The frame each run shows, in run order (A first)."""
        return tuple(f for _, f in self._shown)

    @property
    def frame_times(self) -> tuple[float, ...]:
        """Each run's recording time of the frame it shows, s (0 before the run's offset)."""
        return tuple(t for t, _ in self._shown)

    @property
    def range(self) -> tuple[float, float]:
        """The A/B range in force (the whole recording when unset), s."""
        a = 0.0 if self.a is None else self.a
        b = self.duration if self.b is None else self.b
        return a, b

    def _show(self, pos: float) -> None:
        self._pos = min(max(pos, 0.0), self.duration)
        changed = False
        for i, (rec, off) in enumerate(zip(self.recordings, self.offsets)):
            hit = rec.frame_at(self._pos - off)
            if hit is not None and hit[1] is not self._shown[i][1]:
                self._shown[i] = hit
                changed = True
        if changed:
            self._frame = self._shown[0][1]
            started = [off + t for off, (t, _) in zip(self.offsets, self._shown) if off <= self._pos]
            self._frame_t = max(started) if started else self._pos
            self.version += 1

    # ------------------------------------------------------------------ commands
    def seek(self, t: float) -> Frame:
        """Jump to timeline time ``t`` s (one run: its recording time; clamped to the timeline); returns the
        frame shown (run A's)."""
        if not math.isfinite(t):
            raise ValueError(f"seek time must be a finite number of seconds, got {t!r}")
        with self._lock:
            self._show(t)
            self._last = None
            return self.frame

    def play(self) -> None:
        """Start playing at the current rate (from A when outside the range or at its end)."""
        with self._lock:
            a, b = self.range
            if self._pos < a or self._pos >= b:
                self._show(a)
            self.playing = True
            self._last = None

    def pause(self) -> None:
        with self._lock:
            self.playing = False
            self._last = None

    def toggle(self) -> bool:
        """Play if paused, pause if playing; returns the new ``playing``."""
        if self.playing:
            self.pause()
        else:
            self.play()
        return self.playing

    def step(self, n: int = 1) -> Frame:
        """Pause and move ``n`` frames forward (negative: backward); stops at the ends."""
        with self._lock:
            self.playing = False
            self._last = None
            for _ in range(abs(int(n))):
                hit = self._next_time(forward=n > 0)
                if hit is None:
                    break
                self._show(hit)
            return self.frame

    def _next_time(self, forward: bool) -> float | None:
        """The timeline time of the next (previous) frame of any run after (before) the ones shown, or None."""
        best: float | None = None
        for rec, off, (t, _) in zip(self.recordings, self.offsets, self._shown):
            started = off <= self._pos
            if forward:
                hit = rec.frame_after(t) if started else (0.0, None)
                if hit is not None and (best is None or off + hit[0] < best):
                    best = off + hit[0]
            elif started:
                hit = rec.frame_before(t)
                if hit is not None and (best is None or off + hit[0] > best):
                    best = off + hit[0]
        return best

    def set_rate(self, rate: float) -> None:
        """Playback rate, ×; ValueError outside [0.1, 4]."""
        if not (isinstance(rate, (int, float)) and RATE_MIN - 1e-9 <= rate <= RATE_MAX + 1e-9):
            raise ValueError(f"rate must be between {RATE_MIN}x and {RATE_MAX}x, got {rate!r}")
        with self._lock:
            self.rate = float(rate)

    def set_loop(self, on: bool) -> None:
        self.loop = bool(on)

    def set_range(self, a: float | None, b: float | None) -> None:
        """Restrict play/loop to [a, b] s (None: the recording's start/end); ValueError if a ≥ b."""
        aa = 0.0 if a is None else min(max(float(a), 0.0), self.duration)
        bb = self.duration if b is None else min(max(float(b), 0.0), self.duration)
        if not aa < bb:
            raise ValueError(f"A/B range needs A < B, got A={aa:.3f} s, B={bb:.3f} s")
        with self._lock:
            self.a, self.b = (None if a is None else aa), (None if b is None else bb)

    def set_a(self) -> None:
        """A := the current position (B is dropped if it is not after A)."""
        with self._lock:
            b = self.b if self.b is not None and self.b > self._pos else None
            if b is None and self._pos >= self.duration:
                raise ValueError("A at the very end leaves an empty range")
            self.set_range(self._pos, b)

    def set_b(self) -> None:
        """B := the current position (A is dropped if it is not before B)."""
        with self._lock:
            a = self.a if self.a is not None and self.a < self._pos else None
            self.set_range(a, self._pos)

    def clear_range(self) -> None:
        with self._lock:
            self.a = self.b = None

    def update(self, now: float | None = None) -> bool:
        """Advance a playing timeline to clock time ``now`` (s); True when the shown frame changed."""
        with self._lock:
            t = self._clock() if now is None else float(now)
            if not self.playing:
                self._last = t
                return False
            if self._last is None:
                self._last = t
                return False
            before = self.version
            pos = self._pos + (t - self._last) * self.rate
            self._last = t
            a, b = self.range
            if pos >= b:
                if self.loop and b > a:
                    pos = a + (pos - b) % (b - a)
                else:
                    pos = b
                    self.playing = False
            self._show(pos)
            return self.version != before


def recorded_events(recording: Recording, offset: float = 0.0, prefix: str = "") -> list[tuple[float, str, int]]:
    """The recording's events, repeats collapsed (:class:`~swarmdeck.console.web.events.EventLog`):
    (session time s, text, repeats), oldest first. With several runs: times moved by the run's timeline
    ``offset`` s and texts prefixed with the run's name (``prefix``, "A: ")."""
    from swarmdeck.console.web.events import EventLog

    log = EventLog(MAX_EVENTS)
    for e in recording.events():
        log.add(e.t + offset, prefix + e.text)
    return log.rows()


def timeline_events(recordings: Sequence[Recording], offsets: Sequence[float],
                    names: Sequence[str]) -> list[tuple[float, str, int]]:
    """Every run's events on the timeline, "A: text", in time order (stable: run A first at equal times)."""
    if len(recordings) == 1:
        return recorded_events(recordings[0])
    rows = [row for rec, off, name in zip(recordings, offsets, names)
            for row in recorded_events(rec, off, f"{name}: ")]
    return sorted(rows, key=lambda r: r[0])[:MAX_EVENTS]


class PlayerApp:
    """A recording (or several on one timeline) in the browser: the console's scene + a timeline panel.

    Args:
        recording: an open recording, or several (run A first: drawn solid; the others as ghosts over it or
            beside it, :mod:`~swarmdeck.console.web.compare_view`).
        host, port: where viser listens (port 0 = any free port).
        clock: for the playback thread.
        offsets: each run's timeline offset, s (:mod:`~swarmdeck.console.recording.align`; None: all at 0).
        layout: ``overlay`` or ``side`` (several runs only).
    """

    def __init__(self, recording: Recording | Sequence[Recording], host: str = "127.0.0.1", port: int = 8080,
                 clock: Callable[[], float] = time.monotonic, offsets: Sequence[float] | None = None,
                 layout: str = "overlay") -> None:
        import viser  # here, not at the top: the timeline (Player) works without the browser side

        from swarmdeck.console.recording.metrics import run_letter
        from swarmdeck.console.web.battery_panel import BatteryPanel
        from swarmdeck.console.web.compare_view import LAYOUTS, ComparePlots, GhostRobots
        from swarmdeck.console.web.plots import PlotHistory, PlotsPanel
        from swarmdeck.console.web.scene import LAYERS, ArenaScene

        if layout not in LAYOUTS:
            raise ValueError(f"layout must be one of {', '.join(LAYOUTS)}, got {layout!r}")
        self.player = Player(recording, clock, offsets)
        self.recordings = self.player.recordings
        self.recording = self.recordings[0]
        self.multi = len(self.recordings) > 1
        self.layout = layout
        self.names = tuple(run_letter(i) for i in range(len(self.recordings)))
        first = self.recording.first_frame
        assert first is not None
        self.server: viser.ViserServer = viser.ViserServer(host=host, port=port, verbose=False)
        self.scene: ArenaScene = ArenaScene(self.server, bounds=first.bounds)
        self.ghosts: list[GhostRobots] = []
        self.side_scenes: list[ArenaScene] = []
        if self.multi:
            self._setup_runs(layout)
        self._syncing = False
        self._draw_lock = threading.RLock()
        self._period = 1 / 30
        self._service = ServiceThread(self._run, "swarmdeck-player")
        self.history: PlotHistory = PlotHistory()
        self._drawn_version = -1
        gui = self.server.gui
        gui.configure_theme(show_share_button=False, control_width="large", dark_mode=False,
                            brand_color=(40, 100, 200))
        gui.set_panel_label(f"swarmdeck playback: {self.recording.path.name}" if not self.multi else
                            "swarmdeck playback: " + " · ".join(f"{n} {r.path.name}"
                                                                for n, r in zip(self.names, self.recordings)))
        self.status = gui.add_markdown("")
        dt = max(first.dt, 1e-3)
        self.event_rows = timeline_events(self.recordings, self.player.offsets, self.names)
        if self.multi:
            self._runs_panel(gui)
        with gui.add_folder("Timeline"):
            # a step of 0.01 s: the slider shows "83.20", not "83.204793" (a seek shows the frame at or before it)
            self.slider = gui.add_slider("t (s, timeline)" if self.multi else "t (s, session)", min=0.0, max=round(max(self.player.duration, dt) + 0.005, 2),
                                         step=SLIDER_STEP, initial_value=0.0,
                                         marks=tuple(round(t, 2) for t, _, _ in self.event_rows[:MAX_MARKS]) or None,
                                         hint="The marks are the recording's events (list below)")
            self.play_button = gui.add_button("Play", icon=None)
            self.back_button = gui.add_button("◀ Step")
            self.fwd_button = gui.add_button("Step ▶")
            self.rate = gui.add_dropdown("Rate", tuple(f"{r:g}x" for r in RATES), initial_value="1x")
            self.loop = gui.add_checkbox("Loop", initial_value=False)
            self.a_button = gui.add_button("Set A")
            self.b_button = gui.add_button("Set B")
            self.clear_button = gui.add_button("Clear A/B")
            self.range_text = gui.add_markdown("A/B: whole recording")
        with gui.add_folder("Events"):
            labels = tuple(f"{t:.2f} s · {text}" + (f" × {n}" if n > 1 else "") for t, text, n in self.event_rows)
            self._event_times = dict(zip(labels, (t for t, _, _ in self.event_rows)))  # exact times to seek to
            self.event_select = gui.add_dropdown("Go to event", ("–",) + labels, initial_value="–")
            self.event_list = gui.add_markdown("\n".join(f"- {line}" for line in labels[:MAX_LISTED])
                                               + (f"\n- … {len(labels) - MAX_LISTED} more" if len(labels) > MAX_LISTED
                                                  else "") if labels else "*no events recorded*")
        with gui.add_folder("Layers", expand_by_default=False):
            self._layer_boxes: dict[str, viser.GuiCheckboxHandle] = {}
            for name in LAYERS:
                box = gui.add_checkbox(name, initial_value=self.scene.visible[name])
                box.on_update(lambda _e, n=name, b=box: self._on_layer(n, b.value))
                self._layer_boxes[name] = box
        self.plots: PlotsPanel | None = None if self.multi else PlotsPanel(gui)
        self.compare_plots: ComparePlots | None = ComparePlots(gui, self.names) if self.multi else None
        self.histories: list[PlotHistory] = [PlotHistory() for _ in self.recordings]
        self.batteries = BatteryPanel(gui)
        self.events = gui.add_markdown("")
        self.slider.on_update(lambda _e: self._on_slider())
        self.event_select.on_update(lambda _e: self._on_event())
        self.play_button.on_click(lambda _e: self._on_play())
        self.back_button.on_click(lambda _e: self._after(self.player.step(-1)))
        self.fwd_button.on_click(lambda _e: self._after(self.player.step(1)))
        self.rate.on_update(lambda _e: self.player.set_rate(float(self.rate.value.rstrip("x"))))
        self.loop.on_update(lambda _e: self.player.set_loop(self.loop.value))
        self.a_button.on_click(lambda _e: self._range(self.player.set_a))
        self.b_button.on_click(lambda _e: self._range(self.player.set_b))
        self.clear_button.on_click(lambda _e: self._range(self.player.clear_range))
        self.refresh(force=True)

    @property
    def port(self) -> int:
        return int(self.server.get_port())

    # ------------------------------------------------------------------ several runs
    def _setup_runs(self, layout: str) -> None:
        """The runs after A: ghosts over A's scene (overlay) or their own scenes in a row (side)."""
        from swarmdeck.console.web.compare_view import GhostRobots, row_bounds, run_color, side_offsets
        from swarmdeck.console.web.scene import ArenaScene
        from swarmdeck.core.bounds import Bounds

        sc = self.server.scene
        if layout == "overlay":
            self.ghosts = [GhostRobots(sc, f"/ghosts/{name}", run_color(i))
                           for i, name in enumerate(self.names) if i > 0]
            return
        bounds = [Bounds(*r.first_frame.bounds) for r in self.recordings]  # type: ignore[union-attr]
        shifts = side_offsets(bounds)
        for i, (name, b, dx) in enumerate(zip(self.names, bounds, shifts)):
            if i > 0:
                sc.add_frame(f"/run{name}", show_axes=False, position=(dx, 0.0, 0.0))
                self.side_scenes.append(ArenaScene(self.server, bounds=b, root=f"/run{name}"))
            sc.add_label(f"/titles/{name}", f"{name}: {self.recordings[i].path.name}",
                         position=(b.x_min + dx, b.y_max + 0.08, 0.02), font_size_mode="screen",
                         font_screen_scale=1.0, anchor="bottom-left")
        self.scene.look_at(row_bounds(bounds, shifts))

    def _runs_panel(self, gui: viser.GuiApi) -> None:
        """The "Runs" folder: each run's name, colour, file and offset; show/hide each ghost."""
        from swarmdeck.console.web.compare_view import run_color

        lines = []
        for i, (name, rec, off) in enumerate(zip(self.names, self.recordings, self.player.offsets)):
            r, g, b = run_color(i)
            how = "solid" if i == 0 else ("ghost" if self.layout == "overlay" else "beside")
            lines.append(f"- **{name}** <span style='color:#{r:02x}{g:02x}{b:02x}'>■</span> {rec.path.name} "
                         f"({how}; {rec.duration:.1f} s, starts at {off:.2f} s)")
        with gui.add_folder("Runs"):
            self.runs_text = gui.add_markdown("\n".join(lines))
            self._ghost_boxes = []
            for name, ghost in zip(self.names[1:], self.ghosts):
                box = gui.add_checkbox(f"show {name}", initial_value=True)
                box.on_update(lambda _e, g=ghost, bx=box: g.set_visible(bx.value))
                self._ghost_boxes.append(box)

    # ------------------------------------------------------------------ callbacks
    def _on_layer(self, name: str, visible: bool) -> None:
        self.scene.set_layer(name, visible)
        for other in self.side_scenes:
            other.set_layer(name, visible)
        self.refresh(force=True)

    def _on_slider(self) -> None:
        if self._syncing:
            return
        self.player.seek(float(self.slider.value))
        self.refresh()

    def _on_event(self) -> None:
        t = self._event_times.get(str(self.event_select.value))
        if t is None:  # "–"
            return
        self.player.seek(t)
        self.refresh()

    def _on_play(self) -> None:
        self.player.toggle()
        self.refresh(force=True)

    def _after(self, _frame: Frame) -> None:
        self.refresh()

    def _range(self, action: Callable[[], None]) -> None:
        try:
            action()
        except ValueError as exc:
            self.range_text.content = f"A/B: {exc}"
            return
        a, b = self.player.range
        self.range_text.content = ("A/B: whole recording" if self.player.a is None and self.player.b is None
                                   else f"A/B: {a:.2f} s – {b:.2f} s")

    # ------------------------------------------------------------------ drawing
    def refresh(self, force: bool = False) -> None:
        """Draw the player's frame if it changed, move the slider, update status and plots."""
        with self._draw_lock:  # GUI callbacks and the playback thread both draw
            self._refresh(force)

    def _refresh(self, force: bool) -> None:
        p = self.player
        self.play_button.label = "Pause" if p.playing else "Play"
        if p.version == self._drawn_version and not force:
            return
        self._drawn_version = p.version
        frame = p.frame
        self.scene.draw(frame)
        self._syncing = True
        try:
            self.slider.value = round(p.frame_time, 2)
        finally:
            self._syncing = False
        if self.multi:
            self._refresh_runs()
            return
        hist, last = self.history, self.history.last_time
        if last is not None and not 0.0 < p.frame_time - last <= 1.0:  # a jump: plot the seconds before it
            hist.clear()
            for t, f in self.recording.frames(max(0.0, p.frame_time - PLOT_BACKFILL), p.frame_time):
                hist.add(t, f)
        hist.add(p.frame_time, frame)
        assert self.plots is not None  # one run
        self.plots.show(hist)
        self.batteries.show(frame)
        state = "playing" if p.playing else "paused"
        self.status.content = (f"**{state}** {p.rate:g}x · t = {p.frame_time:.2f} / {p.duration:.2f} s "
                               f"(session) · run t = {frame.run_time:.1f} s · tick {frame.tick} · {frame.n} robots · "
                               f"{frame.behaviour} · {frame.run_state}")
        notes = list(frame.events) + list(frame.alerts)
        self.events.content = "\n".join(f"- {n}" for n in notes[-6:])

    def _refresh_runs(self) -> None:
        """The other runs' ghosts or scenes, the plots with one line per run, the status of each run."""
        p = self.player
        frames, times = p.frames, p.frame_times
        for ghost, f in zip(self.ghosts, frames[1:]):
            ghost.draw(f)
        for scene, f in zip(self.side_scenes, frames[1:]):
            scene.draw(f)
        for hist, rec, off, rt, f in zip(self.histories, self.recordings, p.offsets, times, frames):
            if off > p.position:  # not started yet: no line
                hist.clear()
                continue
            tt, last = off + rt, hist.last_time
            if last is not None and tt == last:
                continue  # this run's frame did not change (it may have ended)
            if last is not None and not 0.0 < tt - last <= 1.0:  # a jump: plot the seconds before it
                hist.clear()
                for t, g in rec.frames(max(0.0, rt - PLOT_BACKFILL), rt):
                    hist.add(off + t, g)
            hist.add(tt, f)
        assert self.compare_plots is not None
        self.compare_plots.show(self.histories)
        self.batteries.show(frames[0])
        state = "playing" if p.playing else "paused"
        lines = [f"**{state}** {p.rate:g}x · t = {p.position:.2f} / {p.duration:.2f} s (timeline)"]
        for name, off, rt, f in zip(self.names, p.offsets, times, frames):
            where = "not started" if off > p.position else f"t = {rt:.2f} s"
            lines.append(f"{name}: {where} · tick {f.tick} · {f.n} robots · {f.behaviour} · {f.run_state}")
        self.status.content = "  \n".join(lines)
        notes = [f"{name}: {n}" for name, f in zip(self.names, frames) for n in (*f.events, *f.alerts)]
        self.events.content = "\n".join(f"- {n}" for n in notes[-6:])

    def _run(self) -> None:
        while not self._service.wait(self._period):
            if self.player.update():
                self.refresh()
            elif not self.player.playing and self.play_button.label != "Play":
                self.refresh(force=True)

    def start(self, period: float = 1 / 30) -> PlayerApp:
        """Start the playback thread (advances and draws every ``period`` s)."""
        self._period = period
        self._service.start()
        return self

    def close(self) -> None:
        self._service.stop()
        self.server.stop()

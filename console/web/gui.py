"""The console's control panel (viser GUI): run/pause/step, emergency stop, behaviour and
barrier parameters, density bumps, layer toggles, live plots, the robots' batteries, the fleet's set-up and
return-to-chargers buttons and the status line.

Every widget lives on ``server.gui`` (shared by all tabs). Callbacks only call
the thread-safe :class:`~swarmdeck.console.runtime.loop.ControlLoop` API, so they take
effect at the next tick. Bad values (out of range, unknown behaviour, a script
that fails to load) are shown as a message in the panel and change nothing.
Assigning a handle's ``.value`` in Python runs the same callbacks (tests).
"""
from __future__ import annotations

import math
import threading
import time
from collections import deque
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from swarmdeck.console.runtime.behaviours import BUILTIN
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.loop import ControlLoop
from swarmdeck.console.runtime.params import BehaviourParams, DensityParams, SafetyParams, Spec, gui_fields
from swarmdeck.console.web.battery_panel import BatteryPanel
from swarmdeck.console.web.events import EventLog
from swarmdeck.console.web.fleet_panel import FleetPanel
from swarmdeck.console.web.plots import PlotHistory, PlotsPanel
from swarmdeck.console.web.scene import LAYERS, ArenaScene

RECENT = 5  # alerts and notices listed (with their session times) under the status line
RELEASE_LABEL = "Release emergency stop (stays paused: then Run)"
RATE_WINDOW = 2.0  # s of loop clock over which "ticks/s" counts ticks

if TYPE_CHECKING:
    import viser
    from viser._gui_handles import GuiModalHandle  # not re-exported by viser 1.1


class TickRate:
    """Ticks per second over the last ``window`` s of the loop's clock: (ticks in the window) / (its span).

    Counted from the Frames' tick indices and times, so Frames the viewer skipped still count and one
    short or long interval moves the figure by no more than its share of the window (an average of
    1/Δt overstated the rate: 26–82 on a 30 Hz loop).
    """

    def __init__(self, window: float = RATE_WINDOW) -> None:
        self.window = float(window)
        self._seen: deque[tuple[float, int]] = deque()  # (Frame.time s, tick), oldest first

    def add(self, time_s: float, tick: int) -> None:
        if self._seen and (tick <= self._seen[-1][1] or time_s <= self._seen[-1][0]):
            self._seen.clear()  # a restart or a clock jump: count afresh
        self._seen.append((float(time_s), int(tick)))
        while len(self._seen) > 2 and self._seen[-1][0] - self._seen[1][0] >= self.window:
            self._seen.popleft()

    @property
    def rate(self) -> float:
        """Ticks/s over the window (0 before two Frames)."""
        if len(self._seen) < 2:
            return 0.0
        (t0, k0), (t1, k1) = self._seen[0], self._seen[-1]
        return (k1 - k0) / (t1 - t0)


def add_param_widget(gui: viser.GuiApi, spec: Spec, value: Any) -> Any:
    """The widget a parameter's declaration asks for (:mod:`swarmdeck.console.runtime.params`): a dropdown
    of its choices, a checkbox for a bool, else a slider over its range with its step."""
    label = spec.label
    if label is None:
        raise ValueError("a parameter without a label is not shown in the GUI (params.gui_fields lists those with one)")
    if spec.choices is not None:
        return gui.add_dropdown(label, spec.choices, initial_value=value)
    if isinstance(value, bool):
        return gui.add_checkbox(label, initial_value=value)
    return gui.add_slider(label, min=spec.lo, max=spec.hi, step=spec.step, initial_value=value)


def widget_value(spec: Spec, handle: Any) -> Any:
    """A parameter widget's value as the parameter's type (str, bool or float)."""
    v = handle.value
    if spec.choices is not None:
        return str(v)
    return v if isinstance(v, bool) else float(v)


def ray_to_floor(origin: ArrayLike, direction: ArrayLike) -> tuple[float, float] | None:
    """Intersect a click ray with the floor z = 0; None when it does not hit it."""
    o = np.asarray(origin, dtype=float)
    d = np.asarray(direction, dtype=float)
    if abs(d[2]) < 1e-9:
        return None
    s = -o[2] / d[2]
    if s <= 0:
        return None
    p = o + s * d
    return float(p[0]), float(p[1])


class ConsoleGui:
    """Builds the panel on ``server.gui`` and keeps it in step with the loop's Frames.

    Args:
        server: the viser server whose ``gui`` and ``scene`` the panel uses.
        loop: the control loop to command.
        scene: the arena scene (for layer toggles).
    """

    #: the density's σ and weight sliders (viser handles from ``_param_widgets``; read by their own callbacks)
    bump_sigma: Any
    bump_weight: Any

    def __init__(self, server: viser.ViserServer, loop: ControlLoop, scene: ArenaScene) -> None:
        self.server, self.loop, self.scene = server, loop, scene
        gui = server.gui
        self.gui: viser.GuiApi = gui
        self._lock = threading.Lock()
        self._reverting = False
        self._bump_handles: dict[int, viser.TransformControlsHandle] = {}
        self.history = PlotHistory()
        self._last_gui_update = 0.0
        self.rate = TickRate()
        self.messages: deque[str] = deque(maxlen=6)
        self.recent = EventLog(RECENT)  # (session t s, text, repeats), newest last

        gui.configure_theme(show_share_button=False, control_width="large", dark_mode=False,
                            brand_color=(40, 100, 200))
        gui.set_panel_label("swarmdeck")
        # The emergency stop first, where the hand expects it: nothing above it grows (events are below).
        self.estop_button = gui.add_button("EMERGENCY STOP", color="red",
                                           hint="Zero every command now (hotkey: space)")
        self.release_button = gui.add_button(RELEASE_LABEL, color="yellow",
                                             hint="The robots stay stopped after the release: press Run to resume")
        self.status = gui.add_markdown("starting…")
        self.alerts = gui.add_markdown("")

        with gui.add_folder("Run"):
            self.run_button = gui.add_button("Run", color="green", icon=None)
            self.pause_button = gui.add_button("Pause", color="gray")
            self.step_button = gui.add_button("Step")
        self.estop_command = gui.add_command("Emergency stop", description="Zero every robot command",
                                             hotkey="space")
        self.run_button.on_click(lambda _: self.loop.run())
        self.pause_button.on_click(lambda _: self.loop.pause())
        self.step_button.on_click(lambda _: self.loop.step())
        self.estop_button.on_click(lambda _: self.loop.estop())
        self.release_button.on_click(lambda _: self.loop.release())
        self.estop_command.on_trigger(lambda _: self.loop.estop())

        bp = loop.behaviour_params
        with gui.add_folder("Behaviour"):
            options = list(BUILTIN)
            if loop.behaviour_name not in options:
                options.append(loop.behaviour_name)
            self.behaviour = gui.add_dropdown("Behaviour", tuple(options), initial_value=loop.behaviour_name)
            self.script_path = gui.add_text("Script path", initial_value="",
                                            hint="A .py file defining behaviour(poses, t) -> (N, 2)")
            self.load_script = gui.add_button("Load script")
            self.params = self._param_widgets(BehaviourParams, bp, lambda name, v: self._set_param(**{name: v}))
        self.behaviour.on_update(self._on_behaviour)
        self.load_script.on_click(self._on_load_script)

        sp = loop.safety_params
        with gui.add_folder("Safety barrier"):
            self.params.update(self._param_widgets(SafetyParams, sp, lambda name, v: self._set_safety(**{name: v}),
                                                   enabled=self._on_barrier_toggle))
        self.barrier_on = self.params["enabled"]
        self.confirm_off: viser.GuiButtonHandle | None = None
        self.cancel_off: viser.GuiButtonHandle | None = None
        self._modal: GuiModalHandle | None = None

        dp = loop.density.params
        with gui.add_folder("Density"):
            self.click_adds = gui.add_checkbox("Click on arena adds a bump", initial_value=True,
                                               hint="Shift-click sends the robots there (goto)")
            self.bump_select = gui.add_dropdown("Bump", ("none",), initial_value="none")
            # bump_sigma / bump_weight: the σ and weight of new bumps, and of the selected one
            self.params.update(self._param_widgets(
                DensityParams, dp, lambda name, v: self._set_density(**{name: v}),
                bump_sigma=lambda _: self._edit_bump(sigma=float(self.bump_sigma.value)),
                bump_weight=lambda _: self._edit_bump(weight=float(self.bump_weight.value))))
            self.bump_sigma, self.bump_weight = self.params["bump_sigma"], self.params["bump_weight"]
            self.bump_remove = gui.add_button("Remove bump")
            self.bump_clear = gui.add_button("Remove all bumps")
        self.bump_select.on_update(self._on_bump_select)
        self.bump_remove.on_click(lambda _: self._remove_selected())
        self.bump_clear.on_click(lambda _: self._remove_all())
        server.scene.on_click()(self._on_scene_click)
        server.scene.on_click(modifier="shift")(self._on_shift_click)

        self.top_view = gui.add_button("Top view", hint="Put this tab's camera back above the arena")
        self.top_view.on_click(self._on_top_view)
        with gui.add_folder("Layers", expand_by_default=False):
            self.layers = {name: gui.add_checkbox(name, initial_value=scene.visible[name]) for name in LAYERS}
        for name, box in self.layers.items():
            box.on_update(lambda _, name=name, box=box: self.scene.set_layer(name, bool(box.value)))

        self.plots = PlotsPanel(gui)
        self.batteries = BatteryPanel(gui, loop.battery_watch)
        self.fleet = FleetPanel(gui, loop, self.notify)

    # ------------------------------------------------------------------ helpers
    def notify(self, text: str, client: viser.ClientHandle | None = None, error: bool = True) -> None:
        """Show a message in the panel (and as a notification to the tab that caused it)."""
        self.messages.append(text)
        self.loop.post(text)
        if client is not None:
            try:
                client.add_notification("swarmdeck", text, auto_close_seconds=6.0, color="red" if error else None)
            except Exception:  # a tab that disconnected mid-update
                pass

    def _param_widgets(self, cls: type, values: Any, change: Any, **special: Any) -> dict[str, Any]:
        """One widget per declared GUI parameter of ``cls`` (initial values from ``values``); a change calls
        ``change(name, value)``, or ``special[name](event)`` for a parameter with its own handling."""
        out: dict[str, Any] = {}
        for name, spec in gui_fields(cls):
            handle = add_param_widget(self.gui, spec, getattr(values, name))
            if name in special:
                handle.on_update(special[name])
            else:
                handle.on_update(lambda _, name=name, spec=spec, handle=handle:
                                 change(name, widget_value(spec, handle)))
            out[name] = handle
        return out

    def _set_density(self, **changes: Any) -> None:
        try:
            self.loop.set_density(**changes)
        except ValueError as exc:
            self.notify(f"density not changed: {exc}")

    def _set_param(self, **changes: Any) -> None:
        try:
            self.loop.set_params(**changes)
        except ValueError as exc:
            self.notify(f"parameter not changed: {exc}")

    def _set_safety(self, **changes: Any) -> None:
        try:
            self.loop.set_safety(**changes)
        except ValueError as exc:
            self.notify(f"barrier not changed: {exc}")

    def _on_behaviour(self, event: viser.GuiEvent) -> None:
        if self._reverting:
            return
        try:
            self.loop.set_behaviour(str(self.behaviour.value))
        except ValueError as exc:
            self.notify(f"behaviour not changed: {exc}", getattr(event, "client", None))

    def _on_load_script(self, event: viser.GuiEvent) -> None:
        path = str(self.script_path.value).strip()
        name = f"script:{path}"
        try:
            self.loop.set_behaviour(name)
        except ValueError as exc:
            self.notify(f"script not loaded: {exc}", getattr(event, "client", None))
            return
        opts = tuple(o for o in self.behaviour.options if not o.startswith("script:")) + (name,)
        # Replacing the options drops the old script, the dropdown's value; viser then resets the
        # value to the first option (coverage) and fires on_update: it must not reach the loop.
        self._reverting = True
        try:
            self.behaviour.options = opts
            self.behaviour.value = name
        finally:
            self._reverting = False

    def _on_barrier_toggle(self, event: viser.GuiEvent) -> None:
        if self._reverting:
            return
        if self.barrier_on.value:
            self._set_safety(enabled=True)
            return
        # Turning the barrier off needs a confirmation; until then it stays on.
        self._reverting = True
        try:
            self.barrier_on.value = True
        finally:
            self._reverting = False
        self._open_confirmation()

    def _open_confirmation(self) -> None:
        if self._modal is not None:
            return
        self._modal = self.gui.add_modal("Turn the safety barrier off?")
        with self._modal:
            self.gui.add_markdown("The robots then get their commands unchanged, within the guard: the walls stay "
                                  "hard, and the barrier comes back by itself the first time two robots would come "
                                  "too close or it would have to intervene strongly (BARRIER BACK ON in the alerts). "
                                  "Only do this in simulation or with a hand on the emergency stop.")
            self.confirm_off = self.gui.add_button("Turn barrier OFF", color="red")
            self.cancel_off = self.gui.add_button("Keep it on")
        self.confirm_off.on_click(lambda _: self._close_confirmation(True))
        self.cancel_off.on_click(lambda _: self._close_confirmation(False))

    def _close_confirmation(self, off: bool) -> None:
        if self._modal is not None:
            self._modal.close()
            self._modal = None
        if off:
            self._set_safety(enabled=False)
            self._reverting = True
            try:
                self.barrier_on.value = False
            finally:
                self._reverting = False

    def _on_top_view(self, event: viser.GuiEvent) -> None:
        client = getattr(event, "client", None)
        if client is None:
            return
        cam = self.server.initial_camera
        # position first: viser moves look_at along with the position, then look_at sets the aim
        client.camera.fov = cam.fov
        client.camera.position = cam.position
        client.camera.look_at = cam.look_at
        client.camera.up_direction = cam.up

    # ------------------------------------------------------------------ bumps
    def _on_scene_click(self, event: viser.SceneClickEvent) -> None:
        if not self.click_adds.value:
            return
        hit = ray_to_floor(event.ray_origin, event.ray_direction)
        if hit is None:
            return
        self.add_bump(hit, getattr(event, "client", None))

    def _on_shift_click(self, event: viser.SceneClickEvent) -> None:
        hit = ray_to_floor(event.ray_origin, event.ray_direction)
        if hit is not None:
            self.go_to(hit, getattr(event, "client", None))

    def go_to(self, xy: tuple[float, float], client: viser.ClientHandle | None = None) -> None:
        """Shift-click: switch to ``goto`` with the robots gathering around ``xy`` (m)."""
        x0, x1, y0, y1 = self.loop.config.bounds
        if not (x0 <= xy[0] <= x1 and y0 <= xy[1] <= y1):
            self.notify(f"goal ({xy[0]:.2f}, {xy[1]:.2f}) m is outside the arena", client)
            return
        try:
            self.loop.set_params(goal_centre=(float(xy[0]), float(xy[1])))
            if self.loop.behaviour_name != "goto":
                self.loop.set_behaviour("goto")
        except ValueError as exc:
            self.notify(f"goal not set: {exc}", client)

    def add_bump(self, xy: tuple[float, float], client: viser.ClientHandle | None = None) -> int | None:
        """Add a bump at ``xy`` (m) with the panel's σ and weight, with a drag handle."""
        try:
            bid = self.loop.add_bump(xy, float(self.bump_sigma.value), float(self.bump_weight.value))
        except ValueError as exc:
            self.notify(f"no bump added: {exc}", client)
            return None
        handle = self.server.scene.add_transform_controls(
            f"/bumps/b{bid}", scale=0.3, disable_rotations=True, active_axes=(True, True, False),
            depth_test=False, position=(float(xy[0]), float(xy[1]), 0.02))
        handle.on_update(lambda _, bid=bid, handle=handle: self.loop.move_bump(bid, handle.position[:2]))
        with self._lock:
            self._bump_handles[bid] = handle
        self._refresh_bump_options(select=bid)
        return bid

    def _refresh_bump_options(self, select: int | None = None) -> None:
        with self._lock:
            ids = sorted(self._bump_handles)
        opts = tuple(f"bump {i}" for i in ids) or ("none",)
        self.bump_select.options = opts
        want = f"bump {select}" if select is not None else (opts[-1] if opts else "none")
        if want in opts:
            self.bump_select.value = want

    def selected_bump(self) -> int | None:
        v = str(self.bump_select.value)
        return int(v.split()[1]) if v.startswith("bump ") else None

    def _on_bump_select(self, _: viser.GuiEvent) -> None:
        bid = self.selected_bump()
        b = self.loop.bumps.get(bid) if bid is not None else None
        if b is None:
            return
        self._reverting = True
        try:
            self.bump_sigma.value = b.sigma
            self.bump_weight.value = b.weight
        finally:
            self._reverting = False

    def _edit_bump(self, **changes: float) -> None:
        if self._reverting:
            return
        bid = self.selected_bump()
        if bid is None:
            return
        try:
            self.loop.update_bump(bid, **changes)
        except ValueError as exc:
            self.notify(f"bump not changed: {exc}")

    def _remove_selected(self) -> None:
        bid = self.selected_bump()
        if bid is not None:
            self.remove_bump(bid)

    def remove_bump(self, bid: int) -> None:
        self.loop.remove_bump(bid)
        with self._lock:
            handle = self._bump_handles.pop(bid, None)
        if handle is not None:
            handle.remove()
        self._refresh_bump_options()

    def _remove_all(self) -> None:
        with self._lock:
            ids = list(self._bump_handles)
        for bid in ids:
            self.remove_bump(bid)

    # ------------------------------------------------------------------ per-frame update
    def record(self, frame: Frame) -> None:
        """Add one Frame's numbers to the plot series (cheap; every frame the viewer sees)."""
        self.rate.add(frame.time, frame.tick)
        t = self.session_time(frame)
        for text in frame.events:
            self.recent.add(t, text)
        self.history.add(t, frame)

    def session_time(self, frame: Frame) -> float:
        """s since the session's first Frame: the one time base of the panel, ``swarmdeck info`` and
        ``swarmdeck play`` (module docstring of :mod:`swarmdeck.console.runtime.loop`, "Clocks")."""
        origin = self.loop.time_origin
        return frame.time - (frame.time if origin is None else origin)

    def update(self, frame: Frame, force: bool = False, period: float = 0.25) -> None:
        """Refresh plots and the status line at most every ``period`` s (wall time)."""
        now = time.monotonic()
        if not force and now - self._last_gui_update < period:
            return
        self._last_gui_update = now
        self.plots.show(self.history)
        self.batteries.show(frame)
        self.fleet.show(frame)
        self.status.content = self.status_line(frame)
        self._sync_widgets(frame)
        self.alerts.content = self.alert_text(frame)

    def alert_text(self, frame: Frame) -> str:
        """The alerts standing now (⚠), then the last :data:`RECENT` alerts and notices with their
        session times (older ones drop off, so nothing piles up under the status line)."""
        alerts = list(frame.alerts)
        if frame.coverage is not None and frame.coverage.packing_warning:
            alerts.append(f"packing: {frame.coverage.packing_warning}")
        text = "\n".join(f"- ⚠ {a}" for a in alerts)
        recent = self.recent.lines()
        if recent:
            text += ("\n\n" if text else "") + "\n".join(f"- {line}" for line in recent)
        return text

    def _sync_widgets(self, frame: Frame) -> None:
        """Widgets follow changes made elsewhere (another tab's script, the API, a config file)."""
        barrier_differs = (frame.barrier is not None and frame.barrier.enabled != self.barrier_on.value
                           and self._modal is None)
        if frame.behaviour == self.behaviour.value and not barrier_differs:
            return
        self._reverting = True
        try:
            if frame.behaviour != self.behaviour.value:
                if frame.behaviour not in self.behaviour.options:
                    self.behaviour.options = tuple(o for o in self.behaviour.options
                                                   if not o.startswith("script:")) + (frame.behaviour,)
                self.behaviour.value = frame.behaviour
            if barrier_differs and frame.barrier is not None:
                self.barrier_on.value = frame.barrier.enabled
        finally:
            self._reverting = False

    def status_line(self, frame: Frame) -> str:
        """The status text: state, session time t and run time, tick rate, solver time, robots, input
        sources and their health."""
        b = frame.barrier
        state = {"running": "RUNNING", "paused": "PAUSED", "estop": "**EMERGENCY STOP**"}[frame.run_state]
        resume = " (robots stopped: press Run to resume)" if frame.run_state == "paused" else ""
        t, run_t = self.session_time(frame), frame.run_time
        solve = f"{1e3 * b.solve_time_s:.1f} ms" if b is not None and b.enabled else "off"
        dmin = f"{b.min_distance:.3f} m" if b is not None and math.isfinite(b.min_distance) else "–"
        lines = [
            f"**{state}**{resume} · {frame.behaviour} · N = {frame.n} · t = {t:.1f} s · run t = {run_t:.1f} s "
            "(behaviour clock, stops while paused)",
            f"{self.rate.rate:.1f} ticks/s · tick {1e3 * frame.timing.get('total', 0.0):.1f} ms · barrier {solve}"
            f" · active {b.n_active if b is not None else 0} · min dist {dmin}",
        ]
        if frame.health:
            lines.append(" · ".join(f"{k}: {v}" for k, v in frame.health.items()))
        return "  \n".join(lines)

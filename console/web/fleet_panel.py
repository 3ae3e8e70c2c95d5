"""The Fleet panel: "Set up" (robots to an experiment's start poses) and "Return to chargers".

Both buttons plan a :class:`~swarmdeck.console.runtime.fleet_upkeep.FleetManeuver` from the
loop's latest Frame and hand it to the loop (:meth:`ControlLoop.use_behaviour`), which runs it
through the same safety pipeline as every behaviour (barrier, wheel limits, emergency stop).
"Set up" reads the start poses from the CSV file named in the panel (``x, y, theta`` per robot),
or, with the field empty, makes random start poses for every robot. Bad input (an unreadable or
malformed file, a pose outside the arena or too close to another, too few charged robots) is
shown in the panel and changes nothing. The panel's status line follows the maneuver.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

from swarmdeck.console.runtime.fleet_upkeep import (
    FleetManeuver,
    FleetView,
    UpkeepConfig,
    random_start_poses,
    read_poses_csv,
    return_to_chargers,
    set_up,
    status_ages,
)
from swarmdeck.console.runtime.frame import Frame, filled
from swarmdeck.console.runtime.loop import ControlLoop
from swarmdeck.devices.chargers import ChargerLayout

if TYPE_CHECKING:
    import viser


class FleetPanel:
    """A "Fleet" folder on the console's GUI driving set-up and return through ``loop``.

    Args:
        gui: the viser GUI.
        loop: the control loop.
        notify: ``notify(text, client)`` shows a problem in the panel (``ConsoleGui.notify``).
        chargers: the charging strips (default: along every wall of the loop's arena).
        config: time limit, assignment policy, maneuver tolerances.
    """

    def __init__(self, gui: viser.GuiApi, loop: ControlLoop, notify: Any,
                 chargers: ChargerLayout | None = None, config: UpkeepConfig = UpkeepConfig()) -> None:
        self.loop, self.notify, self.config = loop, notify, config
        self.chargers = chargers if chargers is not None else ChargerLayout(bounds=loop.config.bounds)
        self.maneuver: FleetManeuver | None = None
        with gui.add_folder("Fleet"):
            self.poses_path = gui.add_text("Start poses CSV", initial_value="",
                                           hint="x, y, theta per robot (m, m, rad); empty: random poses for every robot")
            self.set_up_button = gui.add_button("Set up", hint="Assign charged robots and drive them to the start poses")
            self.return_button = gui.add_button("Return to chargers", hint="Dock every robot on a free charger slot")
            self.status = gui.add_markdown("")
        self.set_up_button.on_click(self._on_set_up)
        self.return_button.on_click(self._on_return)

    def _on_set_up(self, event: Any) -> None:
        """The Set up button: set up from the CSV named in the text box, notifying the clicking tab."""
        self.set_up(str(self.poses_path.value).strip(), getattr(event, "client", None))

    def _on_return(self, event: Any) -> None:
        """The Return button: dock every robot, notifying the clicking tab."""
        self.return_to_chargers(getattr(event, "client", None))

    def _view(self) -> tuple[Frame, FleetView]:
        frame = self.loop.latest
        if frame is None:
            raise ValueError("no robots seen yet")
        return frame, FleetView.of(frame, status_ages(self.loop.sink, frame.ids, filled(frame.is_virtual)))

    def set_up(self, path: str = "", client: viser.ClientHandle | None = None) -> FleetManeuver | None:
        """Plan and start a set-up (``path``: the start poses' CSV; empty: random); None if refused."""
        try:
            frame, view = self._view()
            goals = read_poses_csv(path) if path else random_start_poses(frame.n, frame.bounds, self.chargers)
            maneuver = set_up(view, goals, frame.bounds, self.chargers, self.loop.robot,
                              self.config.fleet.safety_distance, self.config, obstacles=frame.obstacles)
        except ValueError as exc:
            self.notify(f"set up not started: {exc}", client)
            return None
        return self._start(maneuver)

    def return_to_chargers(self, client: viser.ClientHandle | None = None) -> FleetManeuver | None:
        """Plan and start the return of every robot on the floor; None if refused."""
        try:
            frame, view = self._view()
            maneuver = return_to_chargers(view, frame.bounds, self.chargers, self.loop.robot, self.config,
                                          obstacles=frame.obstacles)
        except ValueError as exc:
            self.notify(f"return not started: {exc}", client)
            return None
        return self._start(maneuver)

    def _start(self, maneuver: FleetManeuver) -> FleetManeuver:
        self.maneuver = maneuver
        self.loop.use_behaviour(maneuver)
        self.loop.run()  # ignored (and said so) while the emergency stop is engaged
        self.status.content = maneuver.message
        return maneuver

    def show(self, frame: Frame) -> None:
        """The status: the last maneuver's progress or outcome (while it is the loop's behaviour) and
        how many robots are docked ("ready" when all are)."""
        m = self.maneuver
        docked = int((self.chargers.docked_slot(frame.poses) >= 0).sum())
        text = f"{docked}/{frame.n} robots docked" + (" · ready" if docked == frame.n else "")
        if m is not None and frame.behaviour == m.name:
            text = f"{m.message}  \n{text}"
        if text != self.status.content:
            self.status.content = text

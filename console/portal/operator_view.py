"""The operator's viser view of the arena (``swarmdeck server --console-port P``): the running job, live.

The console's own scene (:class:`~swarmdeck.console.web.scene.ArenaScene`) drawn by
its :class:`~swarmdeck.console.web.app.FrameViewer` (latest-frame-wins on its own
thread, so a slow browser never slows the arena), fed with every Frame of the
job the runner is running (:attr:`~.runner.ArenaRunner.frame_listeners`), thinned as the console's is from
:data:`~swarmdeck.console.web.app.THIN_FROM` robots (by each Frame's robot count: jobs differ). It shows;
it does not steer: the emergency stop and the queue are the portal's operator API. With ``--projector`` it has
the projector's folder (:meth:`OperatorView.add_projector`: layers, brightness, blackout).
"""
from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from swarmdeck.console.web.app import FrameViewer, draw_interval
from swarmdeck.console.web.scene import ArenaScene
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.kinematics import GritsBotParams

if TYPE_CHECKING:
    from swarmdeck.console.projector.server import ProjectorServer
    from swarmdeck.console.web.projector_panel import ProjectorPanel

_log = logging.getLogger(__name__)


class OperatorView:
    """A viser server on ``host:port`` showing each Frame :meth:`offer` is given; :meth:`close`."""

    def __init__(self, host: str = "127.0.0.1", port: int = 8080, bounds: Bounds = DEFAULT_BOUNDS) -> None:
        import viser

        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.scene = ArenaScene(self.server, bounds, robot_radius=GritsBotParams().radius)
        self.viewer = FrameViewer(self.scene, interval_for=draw_interval).start()  # thinned from thousands of robots
        self.host = host
        self.projector_panel: ProjectorPanel | None = None  # add_projector

    @property
    def url(self) -> str:
        host = "127.0.0.1" if self.host in ("0.0.0.0", "") else self.host
        return f"http://{host}:{int(self.server.get_port())}"

    def add_projector(self, projector: ProjectorServer) -> ProjectorPanel:
        """The operator page's Projector folder (``swarmdeck server --console-port P --projector``): the projector's
        layers, brightness (opacity) and blackout, one widget per
        :class:`~swarmdeck.console.runtime.params.ProjectorParams` field, as in the console's panel; a refused
        change is counted (``panel.refused``) and logged."""
        from swarmdeck.console.web.projector_panel import ProjectorPanel

        self.projector_panel = ProjectorPanel(self.server.gui, projector, on_error=_log.warning)
        return self.projector_panel

    def offer(self, frame: Any) -> None:
        """Called on the arena's loop thread: hands the Frame to the drawing thread."""
        self.viewer.offer(frame)

    def close(self) -> None:
        self.viewer.stop()
        self.server.stop()

"""The console panel's "Projector" folder: the projector's layers, brightness and blackout.

One widget per :class:`~swarmdeck.console.runtime.params.ProjectorParams` field (built from the declarations, as
the other folders are); a change goes to the :class:`~swarmdeck.console.projector.server.ProjectorServer`, whose
pages redraw at once. Shown only when the console runs with ``--projector``.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

from swarmdeck.console.runtime.params import ProjectorParams, gui_fields
from swarmdeck.console.web.gui import add_param_widget, widget_value

if TYPE_CHECKING:
    import viser

    from swarmdeck.console.projector.server import ProjectorServer


class ProjectorPanel:
    """The folder's widgets (``widgets``: field name → handle) bound to ``projector``."""

    def __init__(self, gui: viser.GuiApi, projector: ProjectorServer) -> None:
        self.projector = projector
        self.widgets: dict[str, Any] = {}
        settings = projector.settings
        calibrated = projector.feed.calibration is not None
        with gui.add_folder("Projector", expand_by_default=False):
            gui.add_markdown(f"[projector page]({projector.url})" + (
                "" if calibrated else " · **no homography**: run `swarmdeck calibrate projector`"))
            for name, spec in gui_fields(ProjectorParams):
                handle = add_param_widget(gui, spec, getattr(settings, name))
                handle.on_update(lambda _, name=name, spec=spec, handle=handle:
                                 self.set(**{name: widget_value(spec, handle)}))
                self.widgets[name] = handle

    def set(self, **changes: Any) -> None:
        """Apply a widget's change (a bad value is refused by ProjectorParams and leaves the settings as they were)."""
        try:
            self.projector.set(**changes)
        except ValueError:
            pass

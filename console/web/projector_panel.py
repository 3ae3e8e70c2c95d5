"""The console panel's "Projector" folder: the projector's layers, brightness and blackout.

One widget per :class:`~swarmdeck.console.runtime.params.ProjectorParams` field (built from the declarations, as
the other folders are); a change goes to the :class:`~swarmdeck.console.projector.server.ProjectorServer`, whose
pages redraw at once. Shown only when the console runs with ``--projector``.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from swarmdeck.console.runtime.params import ProjectorParams, gui_fields
from swarmdeck.console.web.gui import add_param_widget, widget_value

if TYPE_CHECKING:
    import viser

    from swarmdeck.console.projector.server import ProjectorServer


class ProjectorPanel:
    """The folder's widgets (``widgets``: field name → handle) bound to ``projector``; ``on_error`` gets the
    message of a refused change."""

    def __init__(self, gui: viser.GuiApi, projector: ProjectorServer,
                 on_error: Callable[[str], None] | None = None) -> None:
        self.projector = projector
        self._on_error = on_error
        self.refused = 0
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
        """Apply a widget's change; a bad value is refused by ProjectorParams (settings unchanged), counted, and
        its message goes to ``on_error`` (the console: the loop's event line)."""
        try:
            self.projector.set(**changes)
        except ValueError as exc:
            self.refused += 1
            if self._on_error is not None:
                self._on_error(f"projector setting not changed: {exc}")

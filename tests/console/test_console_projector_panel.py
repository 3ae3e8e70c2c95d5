"""The console panel's Projector folder: one widget per declared projector parameter, and a change in the panel
is the projector's setting at once (its pages redraw with it)."""
from __future__ import annotations

import viser

from swarmdeck.console.projector.server import ProjectorServer
from swarmdeck.console.runtime.params import ProjectorParams, gui_fields
from swarmdeck.console.web.projector_panel import ProjectorPanel
from swarmdeck.core.bounds import DEFAULT_BOUNDS


def test_panel_widgets_set_the_projector():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    projector = ProjectorServer(DEFAULT_BOUNDS, None, port=0)
    try:
        said: list[str] = []
        panel = ProjectorPanel(server.gui, projector, on_error=said.append)
        assert sorted(panel.widgets) == sorted(name for name, _ in gui_fields(ProjectorParams))
        version = projector.feed.version()
        panel.widgets["blackout"].value = True
        panel.widgets["opacity"].value = 0.4
        panel.widgets["cells"].value = False
        s = projector.settings
        assert s.blackout is True and s.opacity == 0.4 and s.cells is False
        assert projector.feed.version() == version + 3
        panel.set(opacity=7.0)  # out of range (a stale widget): refused, the settings stay as they were
        assert projector.settings.opacity == 0.4
        assert panel.refused == 1 and "opacity" in said[0]
    finally:
        server.stop()
        projector.close()

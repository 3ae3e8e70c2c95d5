"""The portal operator view's Projector folder (``swarmdeck server --console-port P --projector``): the operator page
has one widget per projector parameter (layers, brightness, blackout), and a change there is the projector's setting
at once; a refused value is counted and leaves the settings as they were."""
from __future__ import annotations

from swarmdeck.console.portal.operator_view import OperatorView
from swarmdeck.console.projector.server import ProjectorServer
from swarmdeck.console.runtime.params import ProjectorParams, gui_fields
from swarmdeck.core.bounds import DEFAULT_BOUNDS


def test_the_operator_page_steers_the_projector():
    view = OperatorView(port=0)
    projector = ProjectorServer(DEFAULT_BOUNDS, None, port=0)
    try:
        panel = view.add_projector(projector)
        assert view.projector_panel is panel
        assert sorted(panel.widgets) == sorted(name for name, _ in gui_fields(ProjectorParams))
        panel.widgets["blackout"].value = True
        panel.widgets["opacity"].value = 0.3
        panel.widgets["annotations"].value = False
        s = projector.settings
        assert s.blackout is True and s.opacity == 0.3 and s.annotations is False
        panel.set(opacity=-1.0)
        assert projector.settings.opacity == 0.3 and panel.refused == 1
    finally:
        projector.close()
        view.close()


"""clarabel's barrier QP with speed cones on a subset of robots (the closed-loop pruned solve uses it)."""
from __future__ import annotations

import numpy as np

from swarmdeck.safety.constraints import Rows
from swarmdeck.safety.qp_clarabel import solve_qp


def test_only_the_chosen_robots_get_the_speed_disc() -> None:
    nominal = np.array([[0.3, 0.0], [0.0, -0.4], [0.1, 0.1]])  # two robots beyond v_max = 0.2
    both = solve_qp(Rows.empty(), nominal, 0.2)
    assert both.ok and np.allclose(np.linalg.norm(both.u[:2], axis=1), 0.2, atol=1e-7)
    one = solve_qp(Rows.empty(), nominal, 0.2, discs=np.array([True, False, False]))
    assert one.ok
    np.testing.assert_allclose(one.u[0], [0.2, 0.0], atol=1e-7)  # projected onto its disc
    np.testing.assert_allclose(one.u[1:], nominal[1:], atol=1e-7)  # no disc: the nominal
    none = solve_qp(Rows.empty(), nominal, 0.2, discs=np.zeros(3, dtype=bool))
    assert none.ok and none.reason == "unconstrained" and np.array_equal(none.u, nominal)

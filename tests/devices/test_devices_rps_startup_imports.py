"""An rps 2.x script's run imports neither numba nor what it does not use (issue 28: start-up of the rps examples).

numba's import and kernel load cost ≈ 0.5 s CPU per process; at rps sizes (≤ SMALL_ROBOTS robots) the barrier's
kernels run in plain Python (the same bits: tests/safety/test_safety_small_kernels.py), so numba stays out of
``sys.modules``: importing the facade and the runner, and running an rps example (the arena's barrier and the
script's own) for 1 s of experiment time. A barrier on more robots still gets the compiled kernels.
Nor scipy at import, nor its k-d trees and sparse matrices in the run (a few robots' geometry is all-pairs:
tests/core/test_core_pairs_within.py; the active set's Cholesky loads only scipy's LAPACK module:
swarmdeck.safety.small_lapack), clarabel, matplotlib
(the script does not touch the figure), the console's viewer, the recording's writers, torch.
Each check in a fresh interpreter (``sys.modules`` of this test process is shared with every other test).
"""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: modules an rps run that does not touch the figure never needs (absent from ``sys.modules`` after it)
NOT_IMPORTED = ("numba", "scipy.linalg", "scipy.spatial", "scipy.sparse", "clarabel", "matplotlib", "viser", "mcap", "torch")
EXAMPLE = ROOT / "tests" / "data" / "rps2_examples" / "master" / "barrier_certificates" / "si_barriers.py"


def _child(code: str, cwd: Path) -> dict:
    out = subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-4000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_an_rps_example_runs_without_numba(tmp_path: Path) -> None:
    script = tmp_path / EXAMPLE.name
    shutil.copy(EXAMPLE, script)
    code = (
        "import json, sys\n"
        "import swarmdeck.devices.rps.robotarium, swarmdeck.devices.rps.utilities.barrier_certificates\n"
        "after_facade = 'numba' in sys.modules\n"
        "from swarmdeck.devices.runner import run_experiment\n"
        "after_runner = 'numba' in sys.modules\n"
        "scipy_at_import = 'scipy' in sys.modules\n"
        f"r = run_experiment({str(script)!r}, duration=1.0, seed=1, rps=True)\n"
        "print(json.dumps({'ok': r.ok, 'error': r.error, 'steps': r.reports[0].validation.steps,\n"
        "                  'facade': after_facade, 'runner': after_runner, 'run': 'numba' in sys.modules,\n"
        "                  'scipy_at_import': scipy_at_import,\n"
        f"                  'loaded': sorted(m for m in {NOT_IMPORTED!r} if m in sys.modules)}}))\n"
    )
    res = _child(code, tmp_path)
    assert res["ok"], res["error"]
    assert res["steps"] > 0
    assert res == {**res, "facade": False, "runner": False, "run": False}, res
    assert not res["scipy_at_import"], "importing the facade and the runner imported scipy"
    assert res["loaded"] == [], f"an rps run imported {res['loaded']}"


def test_a_larger_barrier_loads_the_compiled_kernels(tmp_path: Path) -> None:
    code = (
        "import json, sys\n"
        "import numpy as np\n"
        "from swarmdeck.safety import SafetyFilter\n"
        "from swarmdeck.safety.small_kernels import SMALL_ROBOTS\n"
        "n = SMALL_ROBOTS + 1\n"
        "f = SafetyFilter(robots=n)\n"
        "x = np.column_stack([np.linspace(-1.4, 1.4, n), np.zeros(n)])\n"
        "safe, _ = f.filter(x, np.zeros((n, 2)))\n"
        "print(json.dumps({'numba': 'numba' in sys.modules, 'finite': bool(np.isfinite(safe).all())}))\n"
    )
    assert _child(code, tmp_path) == {"numba": True, "finite": True}


SENSORS_EXAMPLE = ROOT / "tests" / "data" / "rps2_examples" / "master" / "sensors" / "sensor_readings.py"


def test_an_rps_example_reading_its_distance_sensors_runs_without_numba_or_scipy(tmp_path: Path) -> None:
    """sensor_readings.py (ToF sensors against eight obstacle segments) under ``swarmdeck run``: a few robots' rays
    are cast in numpy (the compiled kernels' bits: tests/sensing/test_sensing_small_paths.py). Failed before: the ray
    casts imported numba (and scipy.linalg with it)."""
    script = tmp_path / SENSORS_EXAMPLE.name
    shutil.copy(SENSORS_EXAMPLE, script)
    code = (
        "import json, sys\n"
        "from swarmdeck.console.cli import main\n"
        f"rc = main(['run', {str(script)!r}, '--duration', '1.0', '--seed', '1'])\n"
        "print(json.dumps({'rc': rc, 'loaded': sorted(m for m in ('scipy', *" + repr(NOT_IMPORTED) + ")\n"
        "                                            if m in sys.modules)}))\n"
    )
    res = _child(code, tmp_path)
    assert res == {"rc": 0, "loaded": []}, res

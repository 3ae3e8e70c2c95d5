"""MARBLER (tests/data/marbler) ready to run: a copy with random policy weights, and the environment
(`PYTHONPATH`) under which its own entry point runs as after MARBLER's `pip install -e .`."""
from __future__ import annotations

import os
import re
import shutil
import sys
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data"
# weights of MARBLER's RNNAgent (hidden 128, 5 actions) for a scenario's observation size
SCENARIOS = {"PredatorCapturePrey": ("mappo.th", 4 * 4 + 4), "Warehouse": ("vdn.th", 3 * 6 + 6)}


def marbler_copy(folder: Path, seed: int = 0, episodes: int | None = None) -> Path:
    """MARBLER's files in ``folder`` with random weights for each scenario; returns its ``main.py``.
    ``episodes``: set each scenario config's ``episodes`` (its run length; the code is unchanged)."""
    root = folder / "marbler"
    shutil.copytree(DATA / "marbler", root)
    if episodes is not None:
        for config in (root / "robotarium_gym" / "scenarios").glob("*/config.yaml"):
            text = re.sub(r"^episodes:.*$", f"episodes: {int(episodes)}", config.read_text(), flags=re.MULTILINE)
            config.write_text(text)
    rng = np.random.default_rng(seed)
    for scenario, (name, n_in) in SCENARIOS.items():
        shapes = {"fc1.weight": (128, n_in), "fc1.bias": (128,), "rnn.weight_ih": (384, 128),
                  "rnn.weight_hh": (384, 128), "rnn.bias_ih": (384,), "rnn.bias_hh": (384,),
                  "fc2.weight": (5, 128), "fc2.bias": (5,)}
        with open(root / "robotarium_gym" / "scenarios" / scenario / "models" / name, "wb") as f:
            np.savez(f, **{k: rng.normal(0, 0.3, s).astype(np.float32) for k, s in shapes.items()})
    return root / "robotarium_gym" / "main.py"


def marbler_env(main: Path) -> dict[str, str]:
    """The process environment: MARBLER's root importable (as installed), the shims for its learning part."""
    paths = [str(main.parent.parent), str(DATA / "marbler_shims")]
    return dict(os.environ, PYTHONPATH=os.pathsep.join(paths + [os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep))


def swarmdeck_cli() -> list[str]:
    """The `swarmdeck` command of this environment."""
    return [str(Path(sys.executable).parent / "swarmdeck")]

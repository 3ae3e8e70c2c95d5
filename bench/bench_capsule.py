"""Per-run overhead of the capsule (issue 31 item 1): what a run pays to record what reproduces it.

Run: ``.venv/bin/python bench/bench_capsule.py`` (~1 min). Rows, median (worst) over the repeats, process CPU time:

* the manifest: :func:`~swarmdeck.console.recording.capsule.manifest_for` of a one-file script and of a 20-file script
  folder (1 MB) — the environment's package versions, every file's SHA-256, the run key;
* the recording: a Recorder writing 300 real frames (20 robots, 10 s) with the capsule (manifest record + the files
  as attachments) minus the same without it, and the bytes it adds;
* ``swarmdeck capsule``: :func:`~swarmdeck.console.recording.capsule_zip.write_capsule` of that recording (not per
  run: once per zip), and :func:`~swarmdeck.console.recording.capsule_zip.open_capsule` (checks every hash).

Beside them, the same-process baseline (harness.baseline) and the cost of recording the run itself.
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.recording.capsule import manifest_for
from swarmdeck.console.recording.capsule_zip import open_capsule, script_files, write_capsule
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig

REPEATS = 15
N, TICKS = 20, 300


def main() -> int:
    print(f"capsule overhead — {time.strftime('%Y-%m-%d')}, {harness.machine()}\n")
    base = harness.baseline(clock="cpu")
    loop = ControlLoop(LoopConfig(n_robots=N, seed=1))
    frames = [loop.tick() for _ in range(TICKS)]
    loop.close()
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        one = d / "one.py"
        one.write_bytes(Path(__file__).read_bytes())
        folder = d / "folder"
        folder.mkdir()
        for k in range(20):
            (folder / f"m{k}.py").write_bytes(bytes(range(256)) * 200)  # 51 kB each, 1 MB in all
        (folder / "main.py").write_text("import m0\n")
        run = {"robots": N, "duration": 10.0, "seed": 1}

        def manifest(path: Path) -> object:
            files, entry = script_files(path)
            return manifest_for("run", files, entry=entry, run=run)

        t_one = harness.measure(lambda: manifest(one), REPEATS, clock="cpu", warmup=1)
        t_folder = harness.measure(lambda: manifest(folder), REPEATS, clock="cpu", warmup=1)
        files, entry = script_files(one)
        capsule = manifest_for("run", files, entry=entry, run=run).to_dict()

        def record(with_capsule: bool, name: str) -> None:
            kw = {"capsule": capsule, "capsule_files": files} if with_capsule else {}
            with Recorder(d / name, {"config": {}}, RecorderConfig(foxglove=False), **kw) as rec:
                for f in frames:
                    rec.write_frame(f)

        t_plain = harness.measure(lambda: record(False, "plain.mcap"), 5, clock="cpu", warmup=1)
        t_caps = harness.measure(lambda: record(True, "caps.mcap"), 5, clock="cpu", warmup=1)
        extra_bytes = (d / "caps.mcap").stat().st_size - (d / "plain.mcap").stat().st_size
        t_zip = harness.measure(lambda: write_capsule(d / "caps.mcap", d / "run.zip"), REPEATS, clock="cpu", warmup=1)
        t_open = harness.measure(lambda: open_capsule(d / "run.zip", Path(tempfile.mkdtemp(dir=d))), REPEATS,
                                 clock="cpu", warmup=1)
    print(harness.table_header(["what", "ms CPU, median (worst)"], [False, True]))
    print(harness.table_row("manifest of a one-file script (versions, SHA-256, run key)", t_one.ms(2)))
    print(harness.table_row("manifest of a 21-file, 1 MB script folder", t_folder.ms(2)))
    print(harness.table_row(f"recording {TICKS} frames of {N} robots, without a capsule (for scale)", t_plain.ms(1)))
    print(harness.table_row(f"the same with the capsule (+{extra_bytes} bytes)", t_caps.ms(1)))
    print(harness.table_row("swarmdeck capsule: write run.zip (once per zip)", t_zip.ms(2)))
    print(harness.table_row("open run.zip: check every hash, extract", t_open.ms(2)))
    print(f"\nbaseline (numpy sort, same process): {base.ms(2)} ms CPU")
    return 0


if __name__ == "__main__":
    sys.exit(main())

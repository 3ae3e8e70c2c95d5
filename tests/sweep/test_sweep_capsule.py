"""One run of a sweep reproduced from its capsule (issue 31): `swarmdeck sweep --capsules` records each run and writes
DIR/capsules/KEY.zip; `swarmdeck run KEY.zip` runs that task again in the sandbox and finds the recording bit for bit;
the run's configuration survives the manifest whole; a capsule whose task is malformed is refused by name."""
import json
import zipfile

import pytest

from swarmdeck.console.cli import main
from swarmdeck.console.recording.capsule_zip import CapsuleError, open_capsule
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import SandboxLimits, probe
from swarmdeck.console.sandbox.plant import Disturbances
from swarmdeck.console.sandbox.verification import VerificationConfig
from swarmdeck.console.sweep.capsules import config_dict, config_from_dict, task_args, task_from_capsule
from swarmdeck.core.obstacles import Obstacles

SCRIPT = """
from swarmdeck.devices import params, record_metrics
p = params(gain=1.0, robots=3)

def experiment(arena):
    while True:
        x = arena.positions()
        arena.set_velocities(-p.gain * (x - x.mean(axis=0)))
        record_metrics(spread=float(abs(x - x.mean(axis=0)).max()))
        arena.step()
"""


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_a_sweep_run_is_reproduced_bit_for_bit_from_its_capsule(tmp_path, capsys):
    script = tmp_path / "gather.py"
    script.write_text(SCRIPT)
    out = tmp_path / "out"
    assert main(["sweep", str(script), "--param", "gain=0.7", "--robots", "3", "--duration", "0.5", "--seed", "4",
                 "--workers", "1", "--capsules", "-o", str(out)]) == 0
    assert "capsules:" in capsys.readouterr().out
    (row_file,) = (out / "runs").glob("*.json")
    key = json.loads(row_file.read_text())["key"]
    capsule = out / "capsules" / f"{key}.zip"
    assert sorted(p.name for p in (out / "capsules").iterdir()) == [capsule.name]  # no recording left beside it
    opened = open_capsule(capsule, tmp_path / "opened")
    assert opened.manifest.kind == "verification" and opened.manifest.run["sweep_key"] == key
    assert dict(opened.manifest.run["params"]) == {"gain": 0.7, "robots": 3}
    with open_recording(opened.recording) as rec:
        recorded = rec.count_frames()
    assert recorded >= 10  # 0.5 s of the run, every step
    # the command a researcher types: exit 0, every recorded frame reproduced bit for bit
    assert main(["run", str(capsule)]) == 0, capsys.readouterr()
    assert f"bit-identical: all {recorded} frames reproduce the recording exactly" in capsys.readouterr().out


def test_the_run_configuration_survives_the_manifest_whole():
    cfg = VerificationConfig(n_robots=4, duration=2.5, runs=1, seed=9, disturbances=Disturbances(pose_noise_xy=0.003),
                             limits=SandboxLimits(cpu_s=120), trusted=True, rps=False, paced_runs=0,
                             obstacles=Obstacles.of([[[0.0, -0.5], [0.0, 0.5]]]), bounds=(-1.5, 1.5, -1.0, 1.0),
                             epsilon=0.05, declared_by="--robots", wall_factor=3.0, boot_s=20.0)
    back = config_from_dict(json.loads(json.dumps(config_dict(cfg))))
    assert config_dict(back) == config_dict(cfg) and back.obstacles is not None
    assert back.disturbances == cfg.disturbances and back.limits == cfg.limits and back.jail == cfg.jail


@pytest.mark.parametrize("run, words", [
    ({"mode": "falsify", "index": 0, "config": {}}, "run.mode"),
    ({"mode": "wrapped", "index": -1, "config": {}}, "run.index"),
    ({"mode": "wrapped", "index": 0, "params": [["gain"]], "config": {}}, "run.params"),
    ({"mode": "wrapped", "index": 0, "config": {"duration": 1.0}}, "run.config"),
    ({"mode": "wrapped", "index": 0, "config": []}, "run.config must be an object"),
])
def test_a_malformed_task_is_refused_by_name(run, words):
    with pytest.raises(ValueError, match=words):
        task_from_capsule(run, {"main.py": b"pass\n"}, "main.py")


def test_a_capsule_that_is_not_a_zip_is_refused(tmp_path):
    bad = tmp_path / "bad.zip"
    bad.write_bytes(b"not a zip")
    with pytest.raises(CapsuleError):
        open_capsule(bad, tmp_path / "o")
    assert not zipfile.is_zipfile(bad)


def test_a_verification_capsule_writes_its_params_as_every_capsule_kind_does_and_reads_the_old_form():
    """Sweep runs' capsules wrote ``[[name, value], …]`` while ``run`` and ``portal`` capsules write an object; they
    now write the object too, and a capsule of the old form still reads to the same task."""
    files = {"main.py": b"pass\n"}
    config = config_dict(VerificationConfig(n_robots=2, duration=1.0, runs=1))
    task = task_from_capsule({"mode": "raw", "index": 1, "params": {"gain": 0.5, "label": "x"}, "config": config},
                             files, "main.py")
    assert task.params == (("gain", 0.5), ("label", "x"))
    assert task_args(task)["params"] == {"gain": 0.5, "label": "x"}
    old = task_from_capsule({"mode": "raw", "index": 1, "params": [["gain", 0.5], ["label", "x"]], "config": config},
                            files, "main.py")
    assert old.params == task.params
    with pytest.raises(ValueError, match="run.params"):
        task_from_capsule({"mode": "raw", "index": 1, "params": "gain=1", "config": config}, files, "main.py")

"""`swarmdeck sweep`: the refusals before anything runs (exit 2, naming what is wrong), and one small sweep from the
command line writing every output."""
import csv

import pytest

from swarmdeck.console.cli import main
from swarmdeck.console.sandbox.confinement import probe

SCRIPT = """
from swarmdeck.devices import params, record_metrics
p = params(gain=1.0, robots=3)

def experiment(arena):
    assert arena.n == p.robots
    while True:
        x = arena.positions()
        arena.set_velocities(-p.gain * (x - x.mean(axis=0)))
        record_metrics(n_seen=arena.n)
        arena.step()
"""


@pytest.fixture
def script(tmp_path):
    path = tmp_path / "gather.py"
    path.write_text(SCRIPT)
    return path


@pytest.mark.parametrize("extra, words", [
    (["--param", "gian=1,2"], ["gather.py does not declare a parameter 'gian'", "gain=1.0, robots=3"]),
    (["--param", "gain=0.5:2:0"], ["empty range"]),
    (["--param", "gain=0:1:1000", "--robots", "1:1000:1000"], ["1,000,000 grid points", "--design random"]),
    (["--param", "gain=0:1:400", "--param", "robots=1:400:400"], ["160,000 grid points", "--design random --samples"]),
    (["--param", "gain=0:1:100", "--seeds", "20000"], ["2,000,000 runs"]),
    (["--design", "random"], ["--design random needs --samples"]),
    (["--param", "robots=2,3", "--robots", "4"], ["give the robot counts once"]),
    (["--seeds", "0"], ["--seeds must be >= 1"]),
    (["--workers", "2", "--ray", "auto"], ["give one of them"]),
])
def test_bad_input_is_refused_before_anything_runs(script, tmp_path, capsys, extra, words):
    out = tmp_path / "out"
    assert main(["sweep", str(script), *extra, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    for w in words:
        assert w in err
    assert not (out / "runs").exists()


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_a_sweep_from_the_command_line_writes_its_table_and_report(script, tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["sweep", str(script), "--param", "gain=0.5", "--robots", "2,3", "--duration", "0.5", "--workers", "1",
            "-o", str(out)]
    assert main(argv) == 0
    assert "2 runs (2 run now, 0 from earlier), 0 failed [local]" in capsys.readouterr().out
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [(r["gain"], r["robots"], r["metric_n_seen"]) for r in rows] == [
        ("0.5", "2", "2.0"), ("0.5", "3", "3.0")]  # a script's `robots` parameter is the count
    page = (out / "report.html").read_text()
    assert "Sweep of gather.py" in page and "0 failed" in page
    assert (out / "results.parquet").exists() and (out / "summary.csv").exists()
    assert main(argv) == 0  # again: everything from the cache
    assert "2 runs (0 run now, 2 from earlier)" in capsys.readouterr().out

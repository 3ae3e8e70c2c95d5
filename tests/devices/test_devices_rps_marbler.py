"""MARBLER runs unchanged on the rps facade: its own entry point (`robotarium_gym/main.py`, `robotarium:
False`), under `swarmdeck run`, in both modes. Its learning part (torch, gym) is shimmed in the test only
(tests/data/marbler/README.md)."""
import subprocess

from marbler_fixtures import marbler_copy, marbler_env, swarmdeck_cli


def _run(tmp_path, *extra):
    main = marbler_copy(tmp_path, episodes=2)  # the scenario's config asks for 10: 2 keep the test short
    return subprocess.run([*swarmdeck_cli(), "run", str(main), *extra, "--", "--scenario", "Warehouse"],
                          env=marbler_env(main), capture_output=True, text=True, timeout=600, cwd=tmp_path)


def test_marblers_own_entry_point_runs_its_episodes(tmp_path):
    out = _run(tmp_path)
    assert out.returncode == 0, out.stderr
    assert "Episode 1\n" in out.stdout and "Episode 2\n" in out.stdout  # run_env prints any exception and stops
    assert "Reward: [" in out.stdout and "Distance Travelled:" in out.stdout
    assert out.stdout.count("swarmdeck run report") >= 3  # one Robotarium per reset, each reported


def test_marbler_under_rps_semantics_counts_errors_as_rps(tmp_path):
    out = _run(tmp_path, "--rps-semantics")
    assert out.returncode == 0, out.stderr
    assert "Episode 2\n" in out.stdout
    assert "##### DEBUG OUTPUT #####" in out.stdout  # roboEnv.__del__ calls call_at_scripts_end(), rps 1.x's text
    assert "safety filter: OFF" in out.stdout  # the barrier only where MARBLER calls it

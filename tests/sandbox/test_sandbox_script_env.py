"""The lab's script environment (``--script-env PATH``): a script imports the environment's packages in
both jails, and an import outside it is refused with a message naming the package and how to ask for it."""
import os
import subprocess
import sys

import pytest
from script_env_fixtures import USES_THE_ENV

from swarmdeck.console.sandbox.import_policy import refusal
from swarmdeck.console.sandbox.script_env import PROVIDED, ScriptEnv, create, format_listing, listing


def test_a_script_imports_the_environments_packages(jail_run, env):
    out = jail_run(USES_THE_ENV, script_env=str(env))
    assert out.ok, out.error
    assert out.ticks > 0


@pytest.mark.parametrize("line, package", [
    ("import msgspec", "msgspec"),                       # in swarmdeck's own environment, not the lab's
    ("import torch.nn", "torch"),                        # nowhere
    ("import importlib\nimportlib.import_module('fastapi')", "fastapi"),
    ("import leaky", "msgspec"),                         # a package of the environment reaching outside it
])
def test_an_import_outside_the_environment_is_refused_naming_the_package(jail_run, env, line, package):
    out = jail_run(line + "\n" + USES_THE_ENV, script_env=str(env))
    assert not out.ok
    assert refusal(package) in out.error, out.error
    assert "swarmdeck env" in refusal(package) and "ask the lab" in refusal(package)


def test_without_a_script_environment_scripts_import_swarmdecks_packages(jail_run):
    out = jail_run("import msgspec\nimport numpy as np\n" + USES_THE_ENV.replace("import labtools\nfrom labtools import helper\n", "")
                   .replace('assert helper() == "labtools"\n', "").replace("labtools.GAIN", "0.05"))
    assert out.ok, out.error


def test_the_listing_names_the_environments_packages_and_what_swarmdeck_provides(env):
    info = listing(ScriptEnv.open(env))
    assert {"name": "labtools", "version": "1.2"} in info["packages"]
    assert [p["name"] for p in info["provided"]] == list(PROVIDED) == ["numpy"]
    assert info["script_env"] == str(env.resolve())
    text = format_listing(info)
    assert "labtools" in text and "1.2" in text and "numpy" in text and "ask the lab" in text


def test_environments_that_break_the_rule_are_refused_with_the_reason(tmp_path):
    with pytest.raises(ValueError, match="no such folder"):
        ScriptEnv.open(tmp_path / "missing")
    with pytest.raises(ValueError, match="not a virtual environment"):
        ScriptEnv.open(tmp_path)
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", "--system-site-packages", str(tmp_path / "sys")],
                   check=True)
    with pytest.raises(ValueError, match="system's site-packages"):
        ScriptEnv.open(tmp_path / "sys")
    other = tmp_path / "other"
    (other / "lib" / "python2.7" / "site-packages").mkdir(parents=True)
    (other / "pyvenv.cfg").write_text("home = /usr/bin\nversion = 2.7.18\n")
    with pytest.raises(ValueError, match="made for Python 2.7.18"):
        ScriptEnv.open(other)
    closed = tmp_path / "closed"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(closed)], check=True)
    os.chmod(closed, 0o700)
    with pytest.raises(ValueError, match="readable by every user"):
        ScriptEnv.open(closed)


def test_create_makes_an_environment_that_follows_the_rule(tmp_path):
    made = create(tmp_path / "lab-env")
    assert made.root == (tmp_path / "lab-env").resolve()
    assert "include-system-site-packages = false" in (tmp_path / "lab-env" / "pyvenv.cfg").read_text()
    with pytest.raises(ValueError, match="not an empty folder"):
        create(tmp_path / "lab-env")


def test_an_environment_gone_after_start_is_an_infrastructure_error_not_the_scripts(tmp_path):
    from swarmdeck.console.sandbox.confinement import ConfinementUnavailable, JailConfig
    from swarmdeck.console.sandbox.run import run_sandboxed

    script = tmp_path / "s.py"
    script.write_text(USES_THE_ENV)
    with pytest.raises(ConfinementUnavailable, match="lab's script environment.*no such folder"):
        run_sandboxed(script, lambda n, ic: None, n_robots=2, duration=0.2,
                      jail=JailConfig(script_env=str(tmp_path / "removed")))

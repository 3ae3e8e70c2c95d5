"""The server says at start-up how it confines user code (jail, seccomp filter, cgroup version, uid per run), so an
operator sees at a glance what a run goes without (docs/security.md, "What the operator must do")."""
import os

from portal_fixtures import ServerProcess

from swarmdeck.console.sandbox import cgroups
from swarmdeck.console.sandbox.confinement import JailConfig, choose_jail, describe


def test_describe_names_the_jail_the_filter_and_the_cgroup_version():
    line = describe()
    jail = choose_jail()[0]
    assert line.startswith(f"{jail} jail, seccomp filter, ")
    version = cgroups.version()
    assert (f"cgroup v{version} per run" if version else "NO cgroup per run") in line
    assert line.endswith("a uid per run" if os.geteuid() == 0 else "the server's own uid")


def test_describe_says_when_nothing_confines():
    assert describe(JailConfig(order=("bwrap",), bwrap="/nonexistent/bwrap")).startswith("NOT CONFINED: bwrap: ")


def test_the_server_prints_it_at_start_up(tmp_path):
    server = ServerProcess(tmp_path / "data", "--robots", "2", "--fast")
    try:
        deadline_lines = []
        while not any("user code confined by:" in line for line in deadline_lines):
            deadline_lines.append(server.lines.get(timeout=60))
        line = next(x for x in deadline_lines if "user code confined by:" in x)
        assert line.strip() == f"swarmdeck server: user code confined by: {describe()}"
    finally:
        server.stop()

"""A cgroup per run, in both jails: memory, processes, CPU and cores limited for the run as a whole, created
by the trusted side and removed afterwards; where none can be made, untrusted code is refused unless the
operator allowed it. Each test records which cgroup version it exercised (``cgroup`` user property)."""
import os

import pytest
from jail_fixtures import plant

from swarmdeck.console.sandbox import cgroups
from swarmdeck.console.sandbox.confinement import ConfinementUnavailable, SandboxLimits

needs_cgroup = pytest.mark.skipif(cgroups.probe() is not None, reason=f"no cgroup here: {cgroups.probe()}")

HOG = """
import os, time
def hold(size):
    block = bytearray(size)
    block[::4096] = b"\\1" * len(range(0, size, 4096))   # touch every page
    time.sleep(60)
def experiment(arena):
    children = []
    for _ in range(3):
        pid = os.fork()
        if pid == 0:
            hold({size})
            os._exit(0)
        children.append(pid)
    for pid in children:
        os.waitpid(pid, 0)
    print("ALL CHILDREN DONE")
    arena.step()
"""


def run_groups():
    """This process's runs' groups now, controller → folders (for assertions from the trusted side)."""
    version, parents = cgroups._layout()
    pattern = "run-*" if version == 2 else "swarmdeck-run-*"
    return {c: sorted(p.glob(pattern)) for c, p in parents.items()}


@needs_cgroup
def test_three_children_over_the_runs_memory_limit_end_the_run_naming_the_limit(jail_run, record_property):
    limits = SandboxLimits(memory=256 << 20, tick_s=30.0)
    out = jail_run(HOG.format(size=120 << 20), limits)  # each child alone is far below any per-process limit
    record_property("cgroup", out.cgroup)
    assert out.cgroup in ("v1", "v2")
    assert out.ended_by == "memory" and "memory limit of 256 MiB" in out.error_line, (out.ended_by, out.error)
    assert "ALL CHILDREN DONE" not in out.log


@needs_cgroup
def test_three_children_of_1_2_gib_are_stopped_by_the_default_limit(jail_run, record_property):
    out = jail_run(HOG.format(size=1229 << 20), SandboxLimits(tick_s=60.0))
    record_property("cgroup", out.cgroup)
    assert out.ended_by == "memory" and f"memory limit of {SandboxLimits().memory >> 20} MiB" in out.error_line


@needs_cgroup
def test_the_runs_group_holds_the_limits_while_it_runs(jail_run, record_property):
    version = cgroups._layout()[0]
    files = {"memory": "memory.limit_in_bytes" if version == 1 else "memory.max", "pids": "pids.max",
             "cpu": "cpu.cfs_quota_us" if version == 1 else "cpu.max", "cpuset": "cpuset.cpus",
             "cpuacct": "cpuacct.usage"}  # (v1: the run's CPU time, charged per tick)
    seen = {}

    def make_plant(n, initial):  # called by the trusted side in the middle of the run
        groups = run_groups()
        ours = [f for f in groups["memory"] if (f / files["memory"]).read_text().strip() == str(300 << 20)]
        assert len(ours) == 1
        seen["folders"] = {c: next(f for f in folders if f.name == ours[0].name) for c, folders in groups.items()}
        seen["values"] = {c: (f / files[c]).read_text().strip() for c, f in seen["folders"].items()}
        seen["procs"] = {int(p) for f in seen["folders"].values() for p in (f / "cgroup.procs").read_text().split()}
        return plant(n, initial)

    out = jail_run("def experiment(arena):\n    arena.step()\n",
                   SandboxLimits(memory=300 << 20, processes=20, cpu_cores=0.5), make_plant=make_plant)
    record_property("cgroup", out.cgroup)
    assert out.ok, out.error
    values = seen["values"]
    assert values["pids"] == "22"  # the script's 20 and the jail's own two
    assert values["cpu"] == ("50000" if version == 1 else "50000 100000")
    assert cgroups._cpus(values["cpuset"]) == os.sched_getaffinity(0)  # the cores the trusted thread had
    assert seen["procs"]  # the jail's processes were inside while the script ran
    assert all(not folder.exists() for folder in seen["folders"].values())  # and the group is gone


@needs_cgroup
@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="needs two cores to give the run one")
def test_widening_the_cpu_affinity_beyond_the_runs_cores_has_no_effect(jail_run, record_property):
    given = min(os.sched_getaffinity(0))
    everything = sorted(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {given})  # the trusted thread's cores are the run's cores
    try:
        out = jail_run(f"""
            import os
            try:
                os.sched_setaffinity(0, {everything!r})
                print("SET ok")
            except OSError as exc:
                print("SET refused", exc.errno)
            print("NOW", sorted(os.sched_getaffinity(0)))
            def experiment(arena):
                arena.step()
        """)
    finally:
        os.sched_setaffinity(0, everything)
    record_property("cgroup", out.cgroup)
    assert out.ok, out.error
    assert f"NOW [{given}]" in out.log, out.log


def test_without_a_cgroup_untrusted_code_is_refused_unless_the_operator_allows_it(jail_run, monkeypatch):
    monkeypatch.setattr(cgroups, "_mounts", lambda: [])  # a machine with no cgroup controller mounted
    with pytest.raises(ConfinementUnavailable, match="no cgroup memory or pids controller.*--allow-no-cgroup"):
        jail_run("def experiment(arena):\n    arena.step()\n")
    out = jail_run("def experiment(arena):\n    arena.step()\n", allow_no_cgroup=True)
    assert out.ok and out.cgroup is None
    assert len(out.unhardened) == 1 and out.unhardened[0].startswith("no cgroup")


def test_cli_allow_no_cgroup_runs_and_warns(tmp_path, monkeypatch, capsys):
    import json

    from swarmdeck.console.cli import main

    monkeypatch.setattr(cgroups, "_mounts", lambda: [])
    script = tmp_path / "s.py"
    script.write_text("def experiment(arena):\n    arena.step()\n")
    base = ["run", "--sandbox", str(script), "--robots", "2", "--duration", "0.2", "--json"]
    assert main(base) == 2
    assert "--allow-no-cgroup" in capsys.readouterr().err
    assert main([*base, "--allow-no-cgroup"]) == 0
    captured = capsys.readouterr()
    report = json.loads(captured.out[captured.out.index("{\n"):])
    assert report["cgroup"] is None and report["unhardened"][0].startswith("no cgroup")
    assert "warning: no cgroup" in captured.err


@needs_cgroup
def test_a_missing_cpu_controller_is_named_and_the_run_still_has_its_memory_and_pids_limits(jail_run, monkeypatch):
    if cgroups._layout()[0] != 1:
        pytest.skip("mounts a hierarchy per controller only in cgroup v1")
    real = cgroups._mounts()  # this machine without its cpu and cpuset hierarchies
    monkeypatch.setattr(cgroups, "_mounts", lambda: [m for m in real if not {"cpu", "cpuset"} & m[2]])
    out = jail_run(HOG.format(size=120 << 20), SandboxLimits(memory=256 << 20, tick_s=30.0))
    assert out.ended_by == "memory" and out.cgroup in ("v1", "v2")
    assert out.unhardened == ["the run's cgroup has no cpu or cpuset controller: its CPU time or cores are not "
                              "limited as a whole"]


@needs_cgroup
def test_groups_left_by_a_killed_server_are_swept_but_live_ones_are_not():
    limits = cgroups.CgroupLimits(memory=64 << 20, processes=4, cpu_cores=1.0, cpus=tuple(os.sched_getaffinity(0)))
    stale, fresh, busy = (cgroups.create(limits, name) for name in ("stale", "fresh", "busy"))
    sleeper = os.fork()
    if sleeper == 0:  # pragma: no cover
        import time

        time.sleep(60)
        os._exit(0)
    try:
        for path in busy.procs_files:
            with open(path, "w") as f:
                f.write(str(sleeper))
        for group in (stale, busy):
            for folder in set(group.folders.values()):
                os.utime(folder, (1000.0, 1000.0))  # created long ago
        removed = set(cgroups.sweep())
        # other swarmdecks' leftovers on a shared host (e.g. an earlier CI run killed mid-run) may be swept too
        assert set(stale.folders.values()) <= removed
        assert not removed & {f for g in (fresh, busy) for f in g.folders.values()}
        assert all(f.name.startswith(("swarmdeck-run-", "run-")) for f in removed)
        assert all(f.exists() for g in (fresh, busy) for f in g.folders.values())
    finally:
        os.kill(sleeper, 9)
        os.waitpid(sleeper, 0)
        for group in (stale, fresh, busy):
            assert group.remove() is None

"""The portal's client commands stay thin (issue 26 item 18): `swarmdeck jobs|submit|results|cancel|fleet status`
import only their own module (no numpy, scipy, viser, cv2: measured, each starts in well under 1 s), a closed pipe (`swarmdeck jobs | head -2`) ends them quietly,
and their messages read as sentences."""
from __future__ import annotations

import json
import subprocess
import sys

from portal_fixtures import CLI

HEAVY = ("numpy", "scipy", "viser", "cv2")
PROBE = ("import json, sys\n"  # noqa: UP031  (a %r of a tuple inside a program text)
         "from swarmdeck.console.cli import main\n"
         "code = main(sys.argv[1:])\n"
         "print(json.dumps({'code': code, 'heavy': [m for m in %r if m in sys.modules]}), file=sys.stderr)\n" % (HEAVY,))


def _run(portal, who, *words):  # noqa: F811
    return subprocess.run([sys.executable, "-c", PROBE, *words, "--server", portal.url, "--token", portal.tokens[who]],
                          capture_output=True, text=True, timeout=120)


def test_client_commands_import_no_heavy_module(portal, tmp_path):  # noqa: F811
    script = tmp_path / "spin.py"
    script.write_text("def experiment(arena):\n    arena.step()\n")
    runs = {"jobs": _run(portal, "alice", "jobs"),
            "submit": _run(portal, "alice", "submit", str(script), "--robots", "2", "--duration", "1"),
            "cancel": _run(portal, "alice", "cancel", "1"),
            "results": _run(portal, "alice", "results", "1", "-o", str(tmp_path / "out"), "--no-wait"),
            "fleet status": _run(portal, "op1", "fleet", "status")}
    for name, r in runs.items():
        report = json.loads(r.stderr.strip().splitlines()[-1])
        assert report["heavy"] == [], (name, report, r.stderr)
        assert report["code"] in (0, 1), (name, r.stderr)


def test_a_closed_pipe_ends_the_command_without_a_traceback(portal):  # noqa: F811
    assert portal.submit("alice").status_code == 201
    for words in (["jobs"], ["--help"], ["jobs", "--json"]):
        proc = subprocess.Popen([*CLI, *words, "--server", portal.url, "--token", portal.tokens["alice"]]
                                if words[0] == "jobs" else [*CLI, *words],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        proc.stdout.close()  # as `head` does once it has its lines: every write now fails with EPIPE
        err = proc.stderr.read()
        proc.wait(timeout=120)
        assert "Traceback" not in err and "BrokenPipeError" not in err, (words, err)


def test_cancelling_an_ended_job_says_so_in_a_sentence(portal):  # noqa: F811
    jid = portal.submit("alice").json()["id"]
    base = ["--server", portal.url, "--token", portal.tokens["alice"]]
    first = subprocess.run([*CLI, "cancel", str(jid), *base], capture_output=True, text=True, timeout=120)
    assert first.returncode == 0 and first.stdout.strip() == f"job {jid}: cancelled", first.stderr
    again = subprocess.run([*CLI, "cancel", str(jid), *base], capture_output=True, text=True, timeout=120)
    assert again.returncode == 1
    assert f"job {jid} has already ended (cancelled): there is nothing to cancel" in again.stderr, again.stderr
    assert "cannot become" not in again.stderr


def test_robots_zero_names_the_option():
    for command in ("console", "verify", "run"):
        r = subprocess.run([*CLI, command, *(["x.py"] if command != "console" else []), "--robots", "0"],
                           capture_output=True, text=True, timeout=120)
        assert r.returncode == 2 and "--robots must be >= 1, got 0" in r.stderr and "n_robots" not in r.stderr, \
            (command, r.stderr)

"""A job's results in a few lines: what the job page and ``swarmdeck submit --wait`` show when a run ended.

:func:`results_summary` reads the job, its ``run.json`` and its files; :func:`summary_lines` words it, the same
on the page and in the terminal. Pure Python (the CLI imports it: no numpy).
"""
from __future__ import annotations

from typing import Any

from swarmdeck.console.portal.job import ExportState


def results_summary(job: dict[str, Any], run: dict[str, Any] | None, files: list[dict[str, Any]]) -> dict[str, Any]:
    """``{"job", "state", "ended_by", "barrier", "bypass", "contacts", "setup", "return", "files", "command"}``:
    did the barrier step in (ticks, share, robots), the minimum distance between robot centres (m), contacts,
    the set-up's and return's collisions, the result files and the command that downloads them."""
    run = run or {}
    barrier = run.get("barrier") or None
    contacts = run.get("contacts") or None
    bypass = run.get("bypass") or None
    return {
        "job": job["id"], "state": job["state"], "ended_by": run.get("ended_by"),
        "barrier": barrier, "bypass": bypass,
        "contacts": None if contacts is None else {"count": contacts.get("count", 0),
                                                   "robots": contacts.get("robots", [])},
        "setup": _maneuver(run.get("setup")), "return": _maneuver(run.get("return")),
        "files": [f["name"] for f in files], "exports": job.get("exports"),
        "command": f"swarmdeck results {job['id']} -o job{job['id']}/",
    }


def _maneuver(m: dict[str, Any] | None) -> dict[str, Any] | None:
    return None if not m else {"ok": m.get("ok"), "collisions": m.get("collisions"), "seconds": m.get("seconds")}


def summary_lines(s: dict[str, Any]) -> list[str]:
    """The summary (:func:`results_summary`) as sentences, one per line."""
    lines = []
    b = s.get("barrier")
    bypass = s.get("bypass") or {}
    if bypass.get("granted"):
        revoked = bypass.get("revoked")
        lines.append("Ran without the barrier (an operator approved it), with the guard: "
                     + (f"the bypass was revoked at t = {revoked['t']:.2f} s ({revoked['why']})" if revoked
                        else "the bypass was never revoked") + ".")
    if b:
        n, k = b.get("ticks") or 0, b.get("stepped_in_ticks") or 0
        if k:
            robots = sorted(b.get("robots", {}).items(), key=lambda kv: (-kv[1], int(kv[0])))
            who = ", ".join(f"robot {r} ({t} ticks)" for r, t in robots[:8]) + (" …" if len(robots) > 8 else "")
            lines.append(f"The barrier stepped in on {k} of {n} ticks ({100.0 * k / max(n, 1):.1f} %): {who}.")
        else:
            lines.append(f"The barrier never stepped in ({n} ticks): the script's commands were sent unchanged.")
        if b.get("min_distance_m") is not None:
            lines.append(f"Minimum distance between robot centres: {b['min_distance_m']:.3f} m.")
    c = s.get("contacts")
    if c is not None:
        lines.append("No contact between robots." if not c["count"] else
                     f"{c['count']} contact(s) between robots (robots {', '.join(map(str, c['robots']))}).")
    for key, what in (("setup", "Set-up"), ("return", "Return to the chargers")):
        m = s.get(key)
        if m and m.get("collisions"):
            lines.append(f"{what}: {m['collisions']} collision(s).")
    if s.get("files"):
        more = (" (the CSV, the HTML replay and the video are still being written: `swarmdeck results` waits for "
                "them)" if s.get("exports") == ExportState.WRITING else "")
        lines.append(f"Files: {', '.join(s['files'])}{more}.")
    lines.append(f"Download them: {s['command']}")
    return lines

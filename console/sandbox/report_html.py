"""The verification report as one self-contained HTML page (inline SVG, no scripts, no network).

It shows the verdict and its reasons, the safety score S of every raw run, the
minimum distance between robot centres over time, and where the first contacts
happened, drawn on the arena.
"""
from __future__ import annotations

import html
from typing import Any

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.constants import ROBOT_DIAMETER

COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf")
CONTACT_DISTANCE = ROBOT_DIAMETER  # m: bodies touch


def _esc(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _nothing(why: str) -> str:
    """In place of a chart with nothing to draw: why there is nothing (never an empty frame)."""
    return f'<p class="nothing">{_esc(why)}</p>'


def _no_motion(runs: list[dict[str, Any]]) -> str | None:
    """Why no raw run has anything to plot (None: some raw run moved robots)."""
    raw = [r for r in runs if r["mode"] == "raw"]
    if not raw:
        return "nothing was run: the script was refused before any simulation (see the reasons above)"
    if not any(r["min_distance_series"] for r in raw):
        return "no run moved a robot: every run ended before its first step (see the runs' errors below)"
    return None


def _score_bars(runs: list[dict[str, Any]], width: int = 520, height: int = 160) -> str:
    why = _no_motion(runs)
    raw = [r for r in runs if r["mode"] == "raw" and r["safety_score"] is not None]
    if why is not None or not raw:
        return _nothing(why or "no raw run measured S (see the runs' errors below)")
    bar = (width - 40) / len(raw)
    parts = [f'<svg width="{width}" height="{height + 30}" role="img" aria-label="S per run">',
             f'<line x1="30" y1="{height}" x2="{width}" y2="{height}" stroke="#444"/>',
             f'<text x="0" y="12" font-size="11">1.0</text><text x="0" y="{height}" font-size="11">0</text>']
    for k, r in enumerate(raw):
        s = r["safety_score"]
        h = s * (height - 10)
        x = 30 + k * bar
        colour = "#2ca02c" if s >= 1.0 else "#d62728"
        parts.append(f'<rect x="{x + 2:.1f}" y="{height - h:.1f}" width="{max(bar - 4, 1):.1f}" height="{h:.1f}" '
                     f'fill="{colour}"><title>run {r["index"]}: S = {s:.4f}</title></rect>')
        parts.append(f'<text x="{x + bar / 2:.1f}" y="{height + 14}" font-size="10" text-anchor="middle">{r["index"]}</text>')
    parts.append("</svg>")
    return "".join(parts)


def _distance_plot(runs: list[dict[str, Any]], duration: float, width: int = 520, height: int = 200) -> str:
    why = _no_motion(runs)
    if why is not None:
        return _nothing(why)
    series = [(r["index"], r["min_distance_series"]) for r in runs if r["mode"] == "raw" and r["min_distance_series"]]
    top = max(max(s) for _, s in series) * 1.05 or 1.0
    parts = [f'<svg width="{width}" height="{height + 20}" role="img" aria-label="minimum distance over time">',
             f'<rect x="40" y="0" width="{width - 40}" height="{height}" fill="none" stroke="#444"/>']
    y_contact = height - CONTACT_DISTANCE / top * height
    parts.append(f'<line x1="40" y1="{y_contact:.1f}" x2="{width}" y2="{y_contact:.1f}" stroke="#d62728" stroke-dasharray="4 3"/>'
                 f'<text x="42" y="{y_contact - 3:.1f}" font-size="10" fill="#d62728">contact ({CONTACT_DISTANCE} m)</text>'
                 f'<text x="0" y="12" font-size="10">{top:.2f} m</text><text x="0" y="{height}" font-size="10">0</text>'
                 f'<text x="{width - 60}" y="{height + 14}" font-size="10">{duration:g} s</text>')
    for index, s in series:
        n = len(s)
        pts = " ".join(f"{40 + (width - 40) * k / max(n - 1, 1):.1f},{height - v / top * height:.1f}" for k, v in enumerate(s))
        parts.append(f'<polyline fill="none" stroke="{COLOURS[index % len(COLOURS)]}" stroke-width="1.2" points="{pts}">'
                     f'<title>run {index}</title></polyline>')
    parts.append("</svg>")
    return "".join(parts)


def _arena_plot(runs: list[dict[str, Any]], bounds: Bounds = DEFAULT_BOUNDS,
                scale: float = 160.0) -> str:
    why = _no_motion(runs)
    if why is not None:
        return _nothing(why)
    b = Bounds.of(bounds)
    x0, x1, y0, y1 = b
    w, h = b.width * scale, b.height * scale
    parts = [f'<svg width="{w + 2:.0f}" height="{h + 2:.0f}" role="img" aria-label="first contacts on the arena">',
             f'<rect x="1" y="1" width="{w:.0f}" height="{h:.0f}" fill="#f7f7f2" stroke="#444"/>']
    count = 0
    for r in runs:
        if r["mode"] != "raw":
            continue
        for t, x, y in r["contact_points"][:10]:
            cx, cy = 1 + (x - x0) * scale, 1 + (y1 - y) * scale
            parts.append(f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="5" fill="{COLOURS[r["index"] % len(COLOURS)]}" '
                         f'fill-opacity="0.7"><title>run {r["index"]}, t = {t:.2f} s, ({x:.2f}, {y:.2f}) m</title></circle>')
            count += 1
    parts.append("</svg>")
    note = "" if count else "<p>no contact in any raw run</p>"
    return "".join(parts) + note


def _run_table(runs: list[dict[str, Any]]) -> str:
    if not runs:
        return _nothing("no run")
    rows = ["<tr><th>run</th><th>mode</th><th>ended by</th><th>S</th><th>contacts</th><th>first contact (s)</th>"
            "<th>min distance (m)</th><th>steps too close</th><th>steps outside</th><th>error</th></tr>"]
    for r in runs:
        c, v = r["contacts"] or {}, r["validation"] or {}
        s = "" if r["safety_score"] is None else f"{r['safety_score']:.4f}"
        first = "" if c.get("first_time") is None else f"{c['first_time']:.2f}"
        dmin = "" if r["min_distance"] is None else f"{r['min_distance']:.3f}"
        rows.append(f"<tr><td>{r['index']}</td><td>{r['mode']}</td><td>{_esc(r['ended_by'])}</td><td>{s}</td>"
                    f"<td>{c.get('count', '')}</td><td>{first}</td><td>{dmin}</td>"
                    f"<td>{v.get('steps_with_collision', '')}</td><td>{v.get('steps_with_boundary', '')}</td>"
                    f"<td>{_esc(r['error'] or '')}</td></tr>")
    return "<table>" + "".join(rows) + "</table>"


def _bound(bound: dict[str, Any] | None) -> str:
    """The stated guarantee (REFERENCE.md §17): "P(contact per run) ≤ 1.0 % at 95 % confidence (299 runs, 0 contacts)"."""
    if not bound:
        return ""
    target = ""
    if bound.get("epsilon") is not None:
        target = (f"; required for a bypass: ≤ {100 * bound['epsilon']:g} % — "
                  + ("met" if bound["met"] else "not met" + (f" ({bound['runs_needed']} runs would be needed)"
                                                             if bound.get("runs_needed") else "")))
    return (f"<p class='bound'>guarantee: <b>{_esc(bound['statement'])}</b> "
            f"({_esc(bound['method'])}, from the raw runs without the barrier){_esc(target)}</p>")


def _falsification(found: dict[str, Any] | None) -> str:
    """The falsifier's worst case beside the bound: its statement, the runs it spent, the replay's file."""
    if not found:
        return ""
    spent = (f" ({found['runs']} of {found['budget']} searched runs, {_esc(found['method'])}; "
             f"{_esc(found['not_in_bound'])})")
    replay = (f" — replay: <code>{_esc(found['recording'])}</code> (<code>swarmdeck play</code>)"
              if found.get("recording") else "")
    return f"<p class='falsification'>falsification: <b>{_esc(found['statement'])}</b>{spent}{replay}</p>"


def render_html(report: dict[str, Any]) -> str:
    """The page for a report dict (:meth:`VerificationReport.to_dict`)."""
    duration = report["config"]["duration"]
    sections = []
    for s in report["scripts"]:
        score = ("— (not measured: rejected)" if s["verdict"] == "rejected" and s["safety_score"] is None
                 else "—" if s["safety_score"] is None else f"{s['safety_score']:.4f}")
        reasons = "".join(f"<li>{_esc(r)}</li>" for r in s["reasons"] + s["bypass_refused_because"])
        sections.append(
            f"<section><h2>{_esc(s['script'])}: {_esc(s['verdict'])}</h2>"
            f"<p>safety score S (mean over raw runs): <b>{score}</b>; sha256 {_esc(s['sha256'][:16])}…</p>"
            + _bound(s.get("contact_bound")) + _falsification(s.get("falsification"))
            + (f"<ul>{reasons}</ul>" if reasons else "")
            + "<h3>S per run (no barrier)</h3>" + _score_bars(s["runs"])
            + "<h3>Minimum distance between robots over time (no barrier)</h3>" + _distance_plot(s["runs"], duration)
            + "<h3>Where the first contacts happened (no barrier)</h3>" + _arena_plot(s["runs"])
            + "<h3>Runs</h3>" + _run_table(s["runs"]) + "</section>")
    style = ("body{font-family:sans-serif;margin:2em;max-width:70em}table{border-collapse:collapse;font-size:12px}"
             "td,th{border:1px solid #ccc;padding:2px 6px}h1 .v{padding:0 .3em}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>swarmdeck verification: {_esc(report['verdict'])}</title>"
            f"<style>{style}</style></head><body><h1>Verdict: <span class='v'>{_esc(report['verdict'])}</span></h1>"
            f"<p>{report['config']['runs']} runs per script, {duration:g} s each, seed {report['config']['seed']}; "
            f"report schema {_esc(report['schema'])}</p>" + "".join(sections) + "</body></html>")

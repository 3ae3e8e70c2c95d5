"""A sweep's files: the tidy table (CSV always, Parquet with pyarrow), the summary, the plots (PNG) and the report.

Column order: ``key``, ``point``, the parameters in the axes' order (then the other declared ones the runs used),
``robots``, ``seed``, ``status``, ``error``, ``ended_by``, ``time_s``, the built-in metrics, the script's metrics
(``metric_NAME``, sorted). Empty cells are None (CSV: empty). The table is a function of the rows alone, so
equal runs give equal files.
"""
from __future__ import annotations

import csv
import html
import io
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from swarmdeck.console.sweep.runs import BUILTIN, METRIC_PREFIX
from swarmdeck.console.sweep.summary import by_value, metric_columns, summarise

if TYPE_CHECKING:
    from swarmdeck.console.sweep.campaign import Plan, SweepSpec

_HEAD = ("key", "point")
_AFTER = ("robots", "seed", "status", "error", "ended_by", "time_s", *BUILTIN)
#: metric labels of the plots and the report (unit in brackets)
LABELS = {"contacts": "contacts (count)", "min_distance": "minimum distance (m)",
          "barrier_interventions": "barrier interventions (robot-steps)",
          "coverage_cost_H": "coverage cost H (uniform density)", "time_to_goal": "time to goal (s)"}


def columns(rows: Sequence[dict[str, Any]], names: Sequence[str]) -> list[str]:
    """The table's columns (module docstring) for ``rows`` with swept parameters ``names``."""
    params = [n for n in names if n != "robots"]
    extra = sorted({k for r in rows for k in r} - set(_HEAD) - set(_AFTER) - set(params)
                   - {k for r in rows for k in r if k.startswith(METRIC_PREFIX)} - {"cpu_s"})
    scripts = sorted({k for r in rows for k in r if k.startswith(METRIC_PREFIX)})
    return [*_HEAD, *params, *extra, *_AFTER, *scripts]


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return str(value)


def to_csv(rows: Sequence[dict[str, Any]], cols: Sequence[str]) -> str:
    """CSV text of ``rows`` in ``cols``' order (None → empty; floats as ``repr``, exact)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(cols)
    for r in rows:
        writer.writerow([_cell(r.get(c)) for c in cols])
    return buf.getvalue()


def _write(path: Path, data: str | bytes) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-")
    with os.fdopen(fd, "wb") as f:
        f.write(data.encode("utf-8") if isinstance(data, str) else data)
    os.replace(tmp, path)


def write_parquet(path: Path, rows: Sequence[dict[str, Any]], cols: Sequence[str]) -> bool:
    """The table as Parquet (False: pyarrow is not installed; the CSV has it all)."""
    try:
        import pyarrow as pa  # type: ignore[import-untyped]
        import pyarrow.parquet as pq  # type: ignore[import-untyped]
    except ImportError:
        return False
    data = {c: [r.get(c) for r in rows] for c in cols}
    arrays = {}
    for c, values in data.items():
        kinds = {type(v) for v in values if v is not None}
        if kinds <= {int, float} and float in kinds:  # a column of ints and floats is a float column
            values = [None if v is None else float(v) for v in values]
        elif len(kinds) > 1:
            values = [None if v is None else str(v) for v in values]
        arrays[c] = pa.array(values)
    pq.write_table(pa.table(arrays), str(path))
    return True


def write_plots(folder: Path, rows: Sequence[dict[str, Any]], names: Sequence[str]) -> list[str]:
    """``folder/plots/METRIC-vs-PARAM.png`` for every numeric swept parameter (and the robot count, when several) and
    metric: the mean over the runs at each value (other parameters pooled), one line per robot count, the 95 % CI as
    a band. Returns the file names
    (relative to ``folder``)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    made: list[str] = []
    plots = folder / "plots"
    plots.mkdir(exist_ok=True)
    numeric = [n for n in names if all(isinstance(r.get(n), (int, float)) and not isinstance(r.get(n), bool)
                                       for r in rows if r.get(n) is not None)]
    if "robots" not in numeric and len({r.get("robots") for r in rows} - {None}) > 1:
        numeric.append("robots")  # the robot counts are an axis of the grid too
    for axis in numeric:
        for metric in metric_columns(rows):
            series = by_value(rows, axis, metric)
            if not any(len(p) > 1 for p in series.values()):
                continue
            fig = Figure(figsize=(5.0, 3.2), dpi=100)
            ax = fig.add_subplot()
            for robots, points in sorted(series.items(), key=lambda kv: (kv[0] is None, kv[0] or 0)):
                x = [p[0] for p in points]
                ax.plot(x, [p[1] for p in points], marker="o", label=f"{robots} robots" if robots else None)
                band = [(p[0], float(p[2]), float(p[3])) for p in points if p[2] is not None and p[3] is not None]
                if band:
                    ax.fill_between([b[0] for b in band], [b[1] for b in band], [b[2] for b in band], alpha=0.25)
            ax.set_xlabel(axis)
            ax.set_ylabel(LABELS.get(metric, metric))
            ax.grid(True, alpha=0.3)
            if len(series) > 1:
                ax.legend(fontsize=8)
            fig.tight_layout()
            name = f"plots/{metric}-vs-{axis}.png"
            fig.savefig(folder / name, format="png", metadata={"Software": None})
            made.append(name)
    return made


def _html_table(rows: Sequence[dict[str, Any]], cols: Sequence[str]) -> str:
    def fmt(v: Any) -> str:
        if v is None:
            return ""
        if isinstance(v, float):
            return f"{v:.4g}"
        return html.escape(str(v))

    head = "".join(f"<th>{html.escape(c)}</th>" for c in cols)
    body = "".join("<tr>" + "".join(f"<td>{fmt(r.get(c))}</td>" for c in cols) + "</tr>" for r in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def report_html(spec_json: dict[str, Any], rows: Sequence[dict[str, Any]], summary: Sequence[dict[str, Any]],
                plots: Sequence[str], total: int) -> str:
    """The one-page report: what was swept, how many runs finished and failed, the summary with CIs, the plots,
    the failures (each error once, with its runs)."""
    failed = [r for r in rows if r["status"] != "ok"]
    errors: dict[str, list[str]] = {}
    for r in failed:
        errors.setdefault(str(r.get("error")), []).append(str(r["key"])[:10])
    axes = ", ".join(f"{a['name']} ∈ {{{', '.join(map(str, a['values'][:8]))}{', …' if len(a['values']) > 8 else ''}}}"
                     for a in spec_json.get("axes", [])) or "no parameter"
    status = "complete" if len(rows) == total else f"INCOMPLETE: {len(rows)} of {total} runs finished"
    scols = list(summary[0]) if summary else []
    imgs = "".join(f'<figure><img src="{html.escape(p)}" alt="{html.escape(p)}"></figure>' for p in plots)
    fails = "".join(f"<li><code>{html.escape(e)}</code> — runs {', '.join(ks[:20])}{' …' if len(ks) > 20 else ''}</li>"
                    for e, ks in errors.items())
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>swarmdeck sweep: {html.escape(spec_json.get('script', ''))}</title>
<style>body{{font-family:system-ui,sans-serif;margin:2em;max-width:80em}}table{{border-collapse:collapse;font-size:.85em}}
td,th{{border:1px solid #ccc;padding:.2em .5em;text-align:right}}figure{{display:inline-block;margin:.5em}}
img{{max-width:30em}}</style></head><body>
<h1>Sweep of {html.escape(spec_json.get('script', ''))}</h1>
<p>{html.escape(axes)}; robots {html.escape(str(spec_json.get('robots')))}; {spec_json.get('seeds')} seeds per point;
{html.escape(str(spec_json.get('design')))} design; barrier {'on' if spec_json.get('barrier') else 'off'};
swarmdeck {html.escape(str(spec_json.get('swarmdeck')))}.</p>
<p id="status"><b>{html.escape(status)}</b>; {len(failed)} failed. Table: <a href="results.csv">results.csv</a>
(<a href="results.parquet">results.parquet</a>), summary: <a href="summary.csv">summary.csv</a>.</p>
<h2>Summary (mean and 95 % CI over the seeds)</h2>
{_html_table(summary, scols)}
<h2>Plots</h2>
{imgs or '<p>No parameter with more than one value: nothing to plot.</p>'}
<h2>Failures</h2>
{'<ul>' + fails + '</ul>' if fails else '<p>None.</p>'}
</body></html>
"""


def write_outputs(folder: Path, the_plan: Plan, rows: Sequence[dict[str, Any]], spec: SweepSpec) -> None:
    """Every file of the sweep from the finished ``rows`` (in the plan's order)."""
    import json

    names = [a.name for a in the_plan.axes]
    cols = columns(rows, names)
    _write(folder / "results.csv", to_csv(rows, cols))
    if not write_parquet(folder / "results.parquet", rows, cols):
        stale = folder / "results.parquet"
        if stale.exists():
            stale.unlink()
    summary = summarise(rows, names)
    scols = list(summary[0]) if summary else ["point"]
    _write(folder / "summary.csv", to_csv(summary, scols))
    plots = write_plots(folder, rows, names)
    spec_json = json.loads((folder / "sweep.json").read_text(encoding="utf-8"))
    _write(folder / "report.html", report_html(spec_json, rows, summary, plots, len(the_plan.runs)))

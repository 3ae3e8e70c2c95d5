"""The sweep's files from rows, pure: the 95 % CI against known values, the CSV/Parquet table, the plots (PNG) and
the report."""
import math

import pytest

from swarmdeck.console.sweep.outputs import columns, report_html, to_csv, write_parquet, write_plots
from swarmdeck.console.sweep.summary import mean_ci, summarise


def rows():
    out = []
    for point, gain in enumerate((0.5, 1.0, 2.0)):
        for seed in range(3):
            ok = not (gain == 2.0 and seed == 2)
            out.append({"key": f"k{point}{seed}", "point": point, "gain": gain, "robots": 4, "seed": seed,
                        "status": "ok" if ok else "failed", "error": None if ok else "boom", "ended_by": "duration",
                        "time_s": 1.0, "contacts": 0, "min_distance": 0.1 * (seed + 1) + gain,
                        "barrier_interventions": seed, "coverage_cost_H": None, "time_to_goal": None,
                        **({"metric_err": gain * 10 + seed} if ok else {})})
    return out


def test_the_mean_ci_is_students():
    mean, lo, hi = mean_ci([1.0, 2.0, 3.0])
    half = 4.302652729911275 / math.sqrt(3)  # t(0.975, 2) · s / √n with s = 1
    assert mean == 2.0 and lo == pytest.approx(2.0 - half) and hi == pytest.approx(2.0 + half)
    assert mean_ci([5.0]) == (5.0, None, None) and mean_ci([]) == (None, None, None)


def test_the_summary_counts_failures_and_leaves_them_out():
    summary = summarise(rows(), ["gain"])
    assert [(s["gain"], s["runs"], s["failed"]) for s in summary] == [(0.5, 3, 0), (1.0, 3, 0), (2.0, 3, 1)]
    assert summary[2]["metric_err_mean"] == 20.5 and summary[0]["min_distance_mean"] == pytest.approx(0.7)
    assert "coverage_cost_H_mean" not in summary[0]  # a metric no run has is no column


def test_table_plots_and_report(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    data = rows()
    cols = columns(data, ["gain"])
    assert cols[:3] == ["key", "point", "gain"] and cols[-1] == "metric_err"
    text = to_csv(data, cols)
    assert text.splitlines()[-1].startswith("k22,2,2.0,4,2,failed,boom,duration,1.0,0,") and text.endswith(",\n")
    assert write_parquet(tmp_path / "t.parquet", data, cols)
    table = pq.read_table(tmp_path / "t.parquet")
    assert table.column_names == cols and table.column("metric_err").to_pylist()[-1] is None
    made = write_plots(tmp_path, data, ["gain"])
    assert "plots/metric_err-vs-gain.png" in made and "plots/min_distance-vs-gain.png" in made
    assert not any("vs-robots" in m for m in made)  # one robot count: no such axis
    more = [dict(r, robots=8 if r["seed"] == 1 else 4) for r in data]
    assert "plots/metric_err-vs-robots.png" in write_plots(tmp_path, more, ["gain"])
    assert (tmp_path / made[0]).read_bytes().startswith(b"\x89PNG")
    page = report_html({"script": "a<b>.py", "axes": [{"name": "gain", "values": [0.5, 1.0, 2.0]}]}, data,
                       summarise(data, ["gain"]), made, total=12)
    assert "a&lt;b&gt;.py" in page and "INCOMPLETE: 9 of 12 runs finished" in page and "<code>boom</code>" in page

"""Parameter sweeps and Monte Carlo campaigns over sandboxed simulated runs (``swarmdeck sweep``).

``design`` (axes from ``--param NAME=VALUES``, grid and random designs, the size limits), ``runs`` (one run: its key,
its sandboxed run through verification's executors, its row), ``campaign`` (plan, cache, resume, run), ``summary``
(means and CIs), ``outputs`` (CSV, Parquet, plots, HTML report). The script's side is
:mod:`swarmdeck.devices.experiment_params` (``params``, ``record_metrics``).
"""

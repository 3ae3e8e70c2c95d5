"""Verification runs, the sandbox for user code, and the executors that scale them out.

* :mod:`.verification` — ``verify(scripts, config, executor) -> VerificationReport``, verdicts, the JSON report.
* :mod:`.run` — ``run_sandboxed``: the user's script in a jailed child, poses and commands over a pipe.
* :mod:`.confinement` — ``SandboxLimits``, ``JailConfig``, the two jails, ``probe()`` (can this machine confine?);
  the jail's parts: :mod:`.namespaces` and :mod:`.zygote` (the ``unshare`` jail), :mod:`.seccomp` (the filter),
  :mod:`.keyrings`, :mod:`.uids` (a uid per run), :mod:`.cgroups` (a cgroup per run).
* :mod:`.plant` — the trusted side: ``SandboxPlant`` (the one plant, on an Arena — ``ArenaPlant`` — or the console loop), ``VerificationRobots`` (disturbances, contacts).
* :mod:`.executors` — ``SerialExecutor``, ``LocalPoolExecutor``, ``RayExecutor``.
* :mod:`.report_html` — the self-contained HTML report.
"""

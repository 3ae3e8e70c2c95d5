"""The lab's script environment: the packages users' scripts may import, and nothing else.

The lab makes a virtual environment for the researchers' libraries (scipy, torch,
networkx, … — whatever it decides to support) and names it with ``--script-env PATH``
(``swarmdeck server``, ``swarmdeck verify``, ``swarmdeck run --sandbox``). Every sandboxed
run then binds it read-only in the jail (:func:`swarmdeck.console.sandbox.confinement.jail_layout`)
and the child puts it in force before the script's first line
(:mod:`swarmdeck.console.sandbox.import_policy`): the script imports the standard library,
``swarmdeck`` / ``rps``, the packages swarmdeck provides itself (:data:`PROVIDED`) and the
environment's packages; anything else is refused with a message naming the package and
how to ask for it. Without ``--script-env`` scripts import what swarmdeck's own environment
has, as before.

The rule for the environment (:meth:`ScriptEnv.open` checks it, :func:`create` follows it):

* a virtual environment (``pyvenv.cfg``) of the Python swarmdeck runs on (same major.minor:
  the sandboxed side is swarmdeck's interpreter, which loads the environment's packages);
* without the system's site-packages (``include-system-site-packages = false``), so what it
  lists is what scripts get;
* packages installed normally, not in editable mode (its ``.pth`` files are not run);
* readable by every user (``chmod -R a+rX``): scripts run under a uid of their own;
* swarmdeck's sandboxed side runs in the same process as the script and has loaded
  :data:`PROVIDED` before it: those are swarmdeck's, at swarmdeck's versions, whatever the
  environment holds (:func:`create` pins them to those versions so compiled packages match).

:func:`listing` is what ``swarmdeck env``, the portal's Submit page and ``GET /api/env`` show.
"""
from __future__ import annotations

import importlib.metadata
import os
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarmdeck.console.sandbox.import_policy import ALWAYS, refusal, top_level_modules

#: Packages swarmdeck's sandboxed side loads itself before the script runs: a script may always import
#: them, at swarmdeck's versions (a copy in the script environment is not used).
PROVIDED = ("numpy",)

#: What a researcher is told to do for a package that is not there.
HOW_TO_REQUEST = ("ask the lab to add it to the script environment; `swarmdeck env` (or the portal's Submit page, "
                  "GET /api/env) lists what is there")


@dataclass(frozen=True)
class Package:
    """One installed distribution: its name and version."""

    name: str
    version: str


@dataclass(frozen=True)
class ScriptEnv:
    """A checked script environment (make one with :meth:`open`).

    Attributes:
        root: the virtual environment's folder (resolved).
        site_packages: its ``lib/pythonX.Y/site-packages`` (resolved).
    """

    root: Path
    site_packages: Path

    @classmethod
    def open(cls, path: str | os.PathLike[str]) -> ScriptEnv:
        """The environment at ``path``; ValueError naming what is wrong when it breaks the rule above."""
        root = Path(path).expanduser()
        if not root.is_dir():
            raise ValueError(f"script environment {str(path)!r}: no such folder "
                             "(create one with `swarmdeck env create PATH`)")
        cfg_file = root / "pyvenv.cfg"
        if not cfg_file.is_file():
            raise ValueError(f"script environment {str(path)!r} is not a virtual environment (no pyvenv.cfg); "
                             "create one with `swarmdeck env create PATH`")
        cfg = _read_cfg(cfg_file)
        if cfg.get("include-system-site-packages", "false").lower() == "true":
            raise ValueError(f"script environment {str(path)!r} includes the system's site-packages "
                             "(include-system-site-packages = true): scripts would not get what it lists; "
                             "create it without --system-site-packages")
        here = f"{sys.version_info.major}.{sys.version_info.minor}"
        site = root / "lib" / f"python{here}" / "site-packages"
        if not site.is_dir():
            made = cfg.get("version_info") or cfg.get("version") or "another Python"
            raise ValueError(f"script environment {str(path)!r} was made for Python {made}; scripts run on "
                             f"swarmdeck's Python {here}: create it with that Python (`swarmdeck env create PATH`)")
        closed = [str(p) for p in (root, root / "lib", site.parent, site) if p.stat().st_mode & 0o005 != 0o005]
        if closed:
            raise ValueError(f"script environment {str(path)!r}: {', '.join(closed)} must be readable by every user "
                             f"(scripts run under a uid of their own): chmod -R a+rX {root}")
        return cls(root=root.resolve(), site_packages=site.resolve())

    def packages(self) -> tuple[Package, ...]:
        """The distributions installed in the environment, sorted by name."""
        found = {}
        for dist in importlib.metadata.distributions(path=[str(self.site_packages)]):
            name = dist.metadata["Name"]
            if name:
                found[_normal(name)] = Package(name=name, version=dist.version)
        return tuple(sorted(found.values(), key=lambda p: _normal(p.name)))

    def modules(self) -> frozenset[str]:
        """The top-level names ``import NAME`` finds in the environment."""
        return top_level_modules(self.site_packages)

    def policy(self) -> dict[str, Any]:
        """What the sandboxed child needs to put the environment in force (the ``start`` message's
        ``script_env``): its site-packages as the jail shows it and the importable names."""
        return {"site": str(self.site_packages), "modules": sorted(self.modules() | set(PROVIDED))}


def _read_cfg(path: Path) -> dict[str, str]:
    out = {}
    for line in path.read_text(errors="replace").splitlines():
        key, sep, value = line.partition("=")
        if sep:
            out[key.strip().lower()] = value.strip()
    return out


def _normal(name: str) -> str:
    return name.lower().replace("_", "-").replace(".", "-")


def _version(name: str) -> str | None:
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return None


def listing(env: ScriptEnv | None) -> dict[str, Any]:
    """What scripts can import, as ``swarmdeck env --json`` and ``GET /api/env`` give it.

    Keys: ``script_env`` (the folder, or None when the lab set none), ``python`` (X.Y),
    ``packages`` (``[{"name", "version"}]``: the environment's, or swarmdeck's whole environment
    when none is set), ``provided`` (what swarmdeck provides itself, always importable),
    ``always`` (importable names besides the standard library), ``request`` (how to ask for a package).
    """
    if env is None:
        packages = sorted({_normal(d.metadata["Name"]): Package(d.metadata["Name"], d.version)
                           for d in importlib.metadata.distributions() if d.metadata["Name"]}.values(),
                          key=lambda p: _normal(p.name))
    else:
        packages = list(env.packages())
    return {
        "script_env": None if env is None else str(env.root),
        "python": f"{sys.version_info.major}.{sys.version_info.minor}",
        "packages": [{"name": p.name, "version": p.version} for p in packages],
        "provided": [{"name": n, "version": _version(n)} for n in PROVIDED],
        "always": [n for n in ALWAYS if not n.startswith("_")],
        "request": HOW_TO_REQUEST,
    }


def format_listing(info: dict[str, Any]) -> str:
    """:func:`listing` as text for a terminal."""
    lines = []
    if info["script_env"] is None:
        lines.append("No script environment is set: scripts import what swarmdeck's own environment has "
                     f"(Python {info['python']}):")
    else:
        lines.append(f"Scripts run on Python {info['python']} with the standard library, "
                     f"{' and '.join(info['always'])}, and:")
        lines += [f"  {p['name']} {p['version'] or ''}  (provided by swarmdeck)".rstrip() for p in info["provided"]]
        lines.append(f"the lab's script environment ({info['script_env']}):")
    width = max((len(p["name"]) for p in info["packages"]), default=0)
    lines += [f"  {p['name']:<{width}}  {p['version']}" for p in info["packages"]]
    if not info["packages"]:
        lines.append("  (no packages)")
    if info["script_env"] is not None:
        lines.append(f"Anything else is refused, e.g. {refusal('torch')}.")
        lines.append(f"To get a package: {info['request']}.")
    return "\n".join(lines)


def create(path: str | os.PathLike[str], packages: Sequence[str] = (), *, pip_args: Sequence[str] = ()) -> ScriptEnv:
    """Make a script environment at ``path`` that follows the rule (see the module docstring): a virtual
    environment of this Python without the system's site-packages, then ``pip install packages`` with
    :data:`PROVIDED` pinned to swarmdeck's versions. ValueError when ``path`` exists and is not empty, or
    venv / pip fail (their output in the message)."""
    root = Path(path).expanduser()
    if root.exists() and (not root.is_dir() or any(root.iterdir())):
        raise ValueError(f"{str(path)!r} exists and is not an empty folder")
    made = subprocess.run([sys.executable, "-m", "venv", str(root)], capture_output=True, text=True, check=False)
    if made.returncode != 0:
        raise ValueError(f"python -m venv {root} failed: {(made.stderr or made.stdout).strip()[-800:]}")
    if packages:
        with tempfile.NamedTemporaryFile("w", suffix=".txt", prefix="swarmdeck-provided-", delete=False) as pins:
            pins.write("".join(f"{n}=={v}\n" for n in PROVIDED if (v := _version(n)) is not None))
        try:
            python = root / "bin" / "python"
            done = subprocess.run([str(python), "-m", "pip", "install", "--constraint", pins.name, *pip_args,
                                   *packages], capture_output=True, text=True, check=False)
        finally:
            os.unlink(pins.name)
        if done.returncode != 0:
            raise ValueError(f"pip install {' '.join(packages)} failed: {(done.stderr or done.stdout).strip()[-800:]}")
    return ScriptEnv.open(root)

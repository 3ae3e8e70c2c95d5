"""The sandboxed side of the lab's script environment: what a user's script may import.

Installed by :mod:`swarmdeck.console.sandbox.child` (inside the jail, after the child has
confined itself and before the script's first line) when the lab set a script
environment (``--script-env PATH``, :mod:`swarmdeck.console.sandbox.script_env`). Then:

* the environment's ``site-packages`` (bound read-only in the jail) comes on ``sys.path``
  before swarmdeck's own installed packages;
* code of the user — the script, its sibling modules, and the packages of the script
  environment — may import only the standard library, ``swarmdeck`` and ``rps``, the
  packages swarmdeck provides itself (:data:`swarmdeck.console.sandbox.script_env.PROVIDED`:
  ``numpy``), its own folder's modules and the environment's top-level modules. Any other
  import raises ``ModuleNotFoundError`` naming the package and how to ask for it
  (:func:`refusal`).

swarmdeck's own modules (and the libraries of swarmdeck's environment they use) import
what they need as before: the rule is about what the *user's* code reaches for, judged by
the file of the importing frame. It is the lab's definition of the environment, not a
wall: the jail (read-only files, no network, the seccomp filter, the run's own uid) is
what confines the script, and a script that digs past this rule (e.g. through
``sys.modules``) gains nothing the jail does not already allow. Only the standard library
is imported here: this module runs in every fork of the fork server.
"""
from __future__ import annotations

import builtins
import importlib
import os
import sys
from collections.abc import Iterable
from types import FrameType

#: Always importable by a script: swarmdeck's experiment API and the rps facade.
ALWAYS = ("swarmdeck", "rps", "__future__")

_NOT_MODULES = (".dist-info", ".egg-info", ".data", ".pth", ".egg-link")


def refusal(name: str) -> str:
    """The message a script gets for importing ``name``, a package outside the script environment."""
    return (f"module {name!r} is not in the lab's script environment; ask the lab to add it "
            "(swarmdeck env lists what is there)")


def top_level_modules(folder: str | os.PathLike[str]) -> frozenset[str]:
    """The names ``import NAME`` finds in ``folder`` (a site-packages or a script's folder): packages
    (folders, with or without ``__init__.py``), ``.py`` files and extension modules; never metadata."""
    names = set()
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return frozenset()
    for entry in entries:
        name = entry.name
        if name.startswith(".") or name == "__pycache__" or name.endswith(_NOT_MODULES):
            continue
        try:
            is_dir = entry.is_dir()
        except OSError:
            continue
        if is_dir:
            if name.isidentifier():
                names.add(name)
        elif name.endswith(".py"):
            names.add(name[:-3])
        elif name.endswith((".so", ".pyd")):
            names.add(name.split(".", 1)[0])
    return frozenset(n for n in names if n.isidentifier())


class _Policy:
    """Decides one import: allowed, or refused because user code asked for a package outside the environment."""

    def __init__(self, allowed: frozenset[str], user_dirs: tuple[str, ...]) -> None:
        self.allowed = allowed
        self.user_dirs = tuple(d.rstrip(os.sep) + os.sep for d in user_dirs)
        self.ours = (os.path.dirname(importlib.__file__) + os.sep, __file__)
        self._by_file: dict[str, bool] = {}

    def is_user_file(self, filename: str) -> bool:
        """True when code of ``filename`` is the user's (the script's folder, the script environment, or
        code made at run time, ``<string>``)."""
        known = self._by_file.get(filename)
        if known is None:
            known = filename.startswith("<") or os.path.abspath(filename).startswith(self.user_dirs)
            self._by_file[filename] = known
        return known

    def importer_is_user(self, frame: FrameType | None) -> bool:
        """Walk out of the import machinery to the frame that asked for the import."""
        while frame is not None:
            filename = frame.f_code.co_filename
            if not (filename.startswith("<frozen") or filename.startswith(self.ours)):
                return self.is_user_file(filename)
            frame = frame.f_back
        return False

    def check(self, name: str, frame: FrameType | None) -> None:
        """Raise ModuleNotFoundError (:func:`refusal`) when user code at ``frame`` imports ``name`` outside the
        environment."""
        top = name.partition(".")[0]
        if top and top not in self.allowed and self.importer_is_user(frame):
            raise ModuleNotFoundError(refusal(top), name=top)


class _Finder:
    """First on ``sys.meta_path``: refuses user imports of packages outside the environment (also through
    ``importlib.import_module``) before any other finder looks for them."""

    def __init__(self, policy: _Policy) -> None:
        self.policy = policy

    def find_spec(self, fullname: str, path=None, target=None):  # noqa: ANN001, ANN201 - the finder protocol
        self.policy.check(fullname, sys._getframe(1))
        return None


def install(site_packages: str, modules: Iterable[str], user_dirs: Iterable[str]) -> None:
    """Put the script environment in force for the rest of this process (see the module docstring).

    ``site_packages``: the environment's site-packages, as the jail shows it; ``modules``: the top-level
    names the script may import besides the standard library and :data:`ALWAYS`; ``user_dirs``: the
    folders whose code is the user's (the script's folder; the site-packages is added).
    """
    dirs = tuple(os.path.abspath(d) for d in (*user_dirs, site_packages))
    allowed = set(modules) | set(sys.stdlib_module_names) | set(ALWAYS)
    for folder in dirs[:-1]:
        allowed |= top_level_modules(folder)
    policy = _Policy(frozenset(allowed), dirs)
    at = next((i for i, p in enumerate(sys.path) if "site-packages" in p or "dist-packages" in p), len(sys.path))
    sys.path.insert(at, os.path.abspath(site_packages))
    sys.meta_path.insert(0, _Finder(policy))
    original = builtins.__import__

    def guarded_import(name, globals=None, locals=None, fromlist=(), level=0):  # noqa: A002, ANN001, ANN202
        if level == 0:
            policy.check(name, sys._getframe(1))
        return original(name, globals, locals, fromlist, level)

    builtins.__import__ = guarded_import

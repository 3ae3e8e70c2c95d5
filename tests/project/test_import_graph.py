"""The dependency rules of DESIGN.md hold for every import, at module level or inside a function.

core imports no other swarmdeck package; safety, sensing, coverage and tracking import only core; inputs
imports coverage and core; devices imports safety, sensing and core; the learning environments (envs) import
anything but the console; only the console and the examples (user code, at the top) import the console. Imports are read with ``ast`` from the source
folders named in pyproject.toml, so lazy imports (inside functions, ``importlib.import_module``
with a literal name) count too.
"""
from __future__ import annotations

import ast
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

ALLOWED: dict[str, set[str]] = {
    "core": set(),
    "safety": {"core"},
    "coverage": {"core"},
    "tracking": {"core"},
    "inputs": {"coverage", "core"},
    "sensing": {"core"},
    "devices": {"safety", "sensing", "core"},
    "envs": {"core", "safety", "sensing", "coverage", "tracking", "inputs", "devices"},
    # experiments to copy: user code at the top, like a script `swarmdeck run` runs (one records with the console's recorder)
    "examples": {"core", "safety", "sensing", "coverage", "tracking", "inputs", "devices", "envs", "console"},
    "console": {"core", "safety", "sensing", "coverage", "tracking", "inputs", "devices", "envs", "examples"},
}


def packages() -> dict[str, Path]:
    """Top-level swarmdeck subpackage → its folder, from pyproject.toml's package-dir."""
    dirs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    return {name.split(".")[1]: ROOT / folder for name, folder in dirs.items() if name.count(".") == 1}


def imported_modules(source: str, module: str, is_package: bool) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in ``source`` of module ``module``."""
    found: list[tuple[int, str]] = []
    here = module.split(".") if is_package else module.split(".")[:-1]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = ".".join(here[: len(here) - node.level + 1])
                name = f"{base}.{node.module}" if node.module else base
            else:
                name = node.module or ""
            found.append((node.lineno, name))
            if node.module is None or node.level:  # `from . import x`: x may be a subpackage
                found += [(node.lineno, f"{name}.{alias.name}") for alias in node.names]
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
            func = node.func
            fname = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
            if fname in ("import_module", "__import__") and isinstance(node.args[0].value, str):
                found.append((node.lineno, node.args[0].value))
    return found


def violations(pkg: str, folder: Path) -> list[str]:
    out = []
    for path in sorted(folder.rglob("*.py")):
        rel = path.relative_to(folder).with_suffix("")
        parts = [p for p in rel.parts if p != "__init__"]
        module = ".".join(["swarmdeck", pkg, *parts])
        for line, name in imported_modules(path.read_text(encoding="utf-8"), module, rel.name == "__init__"):
            bits = name.split(".")
            if bits[0] in packages() and bits[0] != pkg:
                out.append(f"{path.relative_to(folder.parent)}:{line} imports bare top-level {name!r} (use swarmdeck.{name})")
            if bits[0] != "swarmdeck" or len(bits) < 2 or bits[1] == pkg:
                continue
            if bits[1] not in ALLOWED[pkg]:
                out.append(f"{path.relative_to(folder.parent)}:{line}: {pkg} imports {name}")
    return out


def test_every_package_has_a_rule() -> None:
    assert set(packages()) == set(ALLOWED)


def test_no_package_imports_one_above_it() -> None:
    found = [v for pkg, folder in packages().items() for v in violations(pkg, folder)]
    assert not found, "imports against DESIGN.md's dependency rules:\n" + "\n".join(found)


def test_lazy_and_relative_imports_are_seen(tmp_path: Path) -> None:
    src = (
        "from . import unicycle\n"
        "def f():\n"
        "    from swarmdeck.devices import Arena\n"
        "    import swarmdeck.console.runtime\n"
        "    importlib.import_module('swarmdeck.inputs')\n"
        "    from ..core import kinematics\n"
    )
    names = {n for _, n in imported_modules(src, "swarmdeck.safety.sub.mod", False)}
    assert names == {"swarmdeck.safety.sub", "swarmdeck.safety.sub.unicycle", "swarmdeck.devices",
                     "swarmdeck.console.runtime", "swarmdeck.inputs", "swarmdeck.safety.core",
                     "swarmdeck.safety.core.kinematics"}
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "mod.py").write_text(src)
    found = violations("safety", tmp_path)
    assert len(found) == 3 and all(f"{tmp_path.name}/sub/mod.py" in v for v in found)
    assert any("safety imports swarmdeck.devices" in v for v in found)


#: inside the console: subpackage → the console subpackages it must not import. The picture of a Frame
#: (console/picture) lies below every renderer, so the recording's renderers (video, Foxglove) never reach
#: up into the viser console (web) for a colour, and the picture reaches into no renderer.
CONSOLE_FORBIDDEN: dict[str, set[str]] = {
    "recording": {"web"},
    "picture": {"web", "recording", "portal", "cli", "sandbox"},
}


def console_violations(console: Path) -> list[str]:
    """``file:line: console.<sub> imports <name>`` for every import against :data:`CONSOLE_FORBIDDEN`."""
    out = []
    for sub, forbidden in CONSOLE_FORBIDDEN.items():
        for path in sorted((console / sub).rglob("*.py")):
            rel = path.relative_to(console).with_suffix("")
            parts = [p for p in rel.parts if p != "__init__"]
            module = ".".join(["swarmdeck", "console", *parts])
            for line, name in imported_modules(path.read_text(encoding="utf-8"), module, rel.name == "__init__"):
                bits = name.split(".")
                if bits[:2] == ["swarmdeck", "console"] and len(bits) > 2 and bits[2] in forbidden:
                    out.append(f"{path.relative_to(console.parent)}:{line}: console.{sub} imports {name}")
    return out


def test_recording_never_imports_web_and_the_picture_imports_no_renderer() -> None:
    found = console_violations(packages()["console"])
    assert not found, "imports against the console's layering:\n" + "\n".join(found)


def test_the_console_layer_rule_sees_lazy_imports(tmp_path: Path) -> None:
    for sub in CONSOLE_FORBIDDEN:
        (tmp_path / sub).mkdir()
    (tmp_path / "recording" / "x.py").write_text("def f():\n    from swarmdeck.console.web.scene import ROBOT\n")
    (tmp_path / "picture" / "y.py").write_text("from ..recording import reader\nimport swarmdeck.console.runtime\n")
    found = console_violations(tmp_path)
    assert len(found) == 3  # the relative import names the package and its module
    assert "console.recording imports swarmdeck.console.web.scene" in found[0]
    assert all("console.picture imports swarmdeck.console.recording" in f for f in found[1:])


# Inside devices (issue 25 item 7): the fleet (devices/fleet/) sits on the robot model, the
# simulator, the pipeline and the robot ports of the devices root, and under the experiment API
# (Arena, the runner, the rps facade), which set robots up from the chargers. So:
#   * no module of the devices root below the experiment API (every devices/*.py but __init__,
#     arena and runner; devices/net/, devices/rps/) imports devices.fleet;
#   * devices.fleet imports nothing of the experiment API (the devices package itself, arena,
#     runner, rps);
#   * no import of a swarmdeck.devices module inside a function anywhere in devices (a lazy import
#     dodging a cycle), but for the rps facade's matplotlib figure (loaded when a script draws).
EXPERIMENT_API = {"swarmdeck.devices", "swarmdeck.devices.arena", "swarmdeck.devices.runner"}
LAZY_ALLOWED = {"swarmdeck.devices.rps.figure", "swarmdeck.devices.rps"}


def _devices_modules() -> list[tuple[str, Path]]:
    folder = packages()["devices"]
    out = []
    for path in sorted(folder.rglob("*.py")):
        parts = [p for p in path.relative_to(folder).with_suffix("").parts if p != "__init__"]
        out.append((".".join(["swarmdeck", "devices", *parts]), path))
    return out


def _imports(module: str, path: Path) -> list[tuple[int, str]]:
    return imported_modules(path.read_text(encoding="utf-8"), module, path.name == "__init__.py")


def _is_in(name: str, package: str) -> bool:
    return name == package or name.startswith(package + ".")


def test_devices_root_below_the_experiment_api_never_imports_the_fleet() -> None:
    found = [f"{path.relative_to(ROOT)}:{line} imports {name}" for module, path in _devices_modules()
             if not _is_in(module, "swarmdeck.devices.fleet") and module not in EXPERIMENT_API
             for line, name in _imports(module, path) if _is_in(name, "swarmdeck.devices.fleet")]
    assert not found, "the devices root imports devices.fleet (the fleet sits above it):\n" + "\n".join(found)


def test_the_fleet_never_imports_the_experiment_api() -> None:
    found = [f"{path.relative_to(ROOT)}:{line} imports {name}" for module, path in _devices_modules()
             if _is_in(module, "swarmdeck.devices.fleet")
             for line, name in _imports(module, path)
             if name in EXPERIMENT_API or _is_in(name, "swarmdeck.devices.rps")]
    assert not found, "devices.fleet imports the experiment API above it:\n" + "\n".join(found)


def lazy_imports(source: str, module: str, is_package: bool) -> list[tuple[int, str]]:
    """(line, module) of the imports made inside a function body of ``source``."""
    found: set[tuple[int, str]] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for inner in ast.walk(node):
                if isinstance(inner, (ast.Import, ast.ImportFrom)):
                    found |= {(inner.lineno, name) for _, name in imported_modules(ast.unparse(inner), module, is_package)}
    return sorted(found)


def test_no_lazy_import_dodges_a_cycle_inside_devices() -> None:
    found = sorted({f"{path.relative_to(ROOT)}: imports {name} inside a function"
                    for module, path in _devices_modules()
                    for _, name in lazy_imports(path.read_text(encoding="utf-8"), module, path.name == "__init__.py")
                    if _is_in(name, "swarmdeck.devices") and name not in LAZY_ALLOWED})
    assert not found, "lazy imports inside devices (import at module level; fix the layering instead):\n" + "\n".join(found)


def test_the_devices_rules_see_a_lazy_fleet_import(tmp_path: Path) -> None:
    src = "def f():\n    from swarmdeck.devices.fleet.manager import FleetManager\n"
    assert lazy_imports(src, "swarmdeck.devices.simulator", False) == [(2, "swarmdeck.devices.fleet.manager")]

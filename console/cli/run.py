"""``swarmdeck run SCRIPT.py``: run a user experiment headless on the simulated arena.

Also the plumbing every headless run shares (``swarmdeck example NAME`` uses it too):
:func:`add_run_arguments`, :func:`check_run_arguments`, :func:`run_headless`,
:func:`raise_if_failed`.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from collections.abc import Callable
from typing import Any

from swarmdeck.console.cli import UsageError
from swarmdeck.console.cli._param_option import param_values
from swarmdeck.core.robot_models import ROBOT_MODELS
from swarmdeck.devices.experiment_params import params_in_environment

NAME = "run"
HELP = "run an experiment script headless on the simulated arena and print its report"
ORDER = 20


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("script", help="Python file defining experiment(arena), or an rps-style script that builds "
                                       "Arena(); or a capsule run.zip (`swarmdeck capsule`): re-executed in simulation "
                                       "and compared with its recording (exit 0 bit-identical, 1 different, 3 identical "
                                       "frames in another environment; with --sandbox its script runs in the jail: do "
                                       "that for a capsule you did not make)")
    parser.add_argument("--robots", type=int, default=None, metavar="N", help="number of robots (default: the script's, else 6)")
    parser.add_argument("--duration", type=float, default=None, metavar="S", help="stop after S simulated seconds")
    parser.add_argument("--seed", type=int, default=None, help="seed for random initial conditions")
    parser.add_argument("--no-safety", action="store_true", help="run without the barrier-certificate safety filter")
    parser.add_argument("--from-docks", action="store_true",
                        help="start the simulated robots docked on the chargers along the walls, set them up to the "
                             "script's initial poses, run, and return them to the chargers; the report says how long "
                             "setup and return took, the largest start-pose error and the collisions")
    parser.add_argument("--robots-via", default=None, metavar="URL",
                        help="run the script on GRITSBots over MQTT instead of the simulation, e.g. "
                             "mqtt://127.0.0.1:1883 (try `swarmdeck robots --broker URL` for a simulated fleet): robots "
                             "0..N-1 of --robots N, through the same safety pipeline; they start where they are (a "
                             "script's initial conditions are not driven to) and each step lasts one period of wall time")
    parser.add_argument("--obstacles", default=None, metavar="FILE",
                        help="line-segment obstacles on the floor: a TOML file with an [arena] table, "
                             "obstacles = [[[x0, y0], [x1, y1]], {polygon = [[x, y], ...]}] in m (as in the "
                             "console's --config); solid in the simulator, kept clear by the barrier")
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.add_argument("--record", default=None, metavar="PATH",
                        help="record the run to PATH (MCAP, as `swarmdeck console --record`: `swarmdeck play PATH`, "
                             "Foxglove), with what the script draws (arena.draw, an rps script's plots on r.axes: "
                             "docs/drawing.md); a script that builds more Arenas records the k-th to PATH-k.mcap")
    parser.add_argument("--foxglove-channels", action=argparse.BooleanOptionalAction, default=True,
                        help="with --record: write Foxglove's own channels (scene, poses, metrics, log) beside "
                             "swarmdeck's (default on; --no-foxglove-channels: a file ≈ 6x smaller at 100 robots, "
                             "still played by `swarmdeck play`)")
    parser.add_argument("--foxglove-entities", action="store_true",
                        help="with --record: the robots for Foxglove as a disc, an arrow and a label each, every frame "
                             "up to 100 robots (≈ 4x larger at 100 robots; default: one packed PointCloud on "
                             "/foxglove/robot_points, 10 scenes/s at 100 robots)")
    parser.add_argument("--rps", action=argparse.BooleanOptionalAction, default=None,
                        help="resolve `import rps...` to swarmdeck's rps facade (default: when no rps is installed)")
    parser.add_argument("--rps-semantics", action="store_true",
                        help="the rps facade behaves as rps: the barrier applies only where the script calls one, "
                             "and collisions, boundary and actuator violations are counted in Robotarium._errors and "
                             "printed by debug()/call_at_scripts_end() as rps prints them (default: every step is "
                             "filtered, as the arena runs it)")
    parser.add_argument("--no-rps-call-order", dest="rps_call_order", action="store_false",
                        help="let the rps facade accept get_poses() twice per step() and step() twice in a row "
                             "(rps and the Robotarium raise an AssertionError)")
    parser.add_argument("--robot-model", choices=sorted(ROBOT_MODELS), default=None,
                        help="the simulated robots: gritsbot (the default) or gternal (Robotarium 2.x: base 0.11 m); "
                             "default for an rps script: the robot of its rps generation (gternal for a 2.x script, "
                             "which ends with r.debug(); gritsbot for 1.x, which ends with r.call_at_scripts_end())")
    parser.add_argument("--rps-generation", type=int, choices=(1, 2), default=None,
                        help="the Robotarium simulator the rps script was written for (default: read from the script)")
    parser.add_argument("--sandbox", action="store_true",
                        help="run the script in a confined child process (no network, read-only files, resource limits); "
                             "swarmdeck keeps the simulator and the safety filter")
    parser.add_argument("--trusted", action="store_true",
                        help="with --sandbox: run unconfined (resource limits only) where this machine cannot confine")
    parser.add_argument("--allow-no-cgroup", action="store_true",
                        help="with --sandbox: run even where no cgroup can be created for the run (not root, no "
                             "memory/pids controller): then only per-process limits bound its memory, processes and CPU")
    parser.add_argument("--jail", choices=("unshare", "bwrap"), default=None,
                        help="with --sandbox: confine with this jail only (default: unshare, then bubblewrap)")
    from swarmdeck.console.cli.env import add_script_env_argument

    add_script_env_argument(parser, "with --sandbox: ")
    parser.add_argument("--entry", default=None, metavar="FILE",
                        help="with --sandbox and a directory SCRIPT: the file to run, relative to it (default main.py); "
                             "sibling modules are importable")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="a value for a parameter the script declares with swarmdeck.devices.params(...) (repeat "
                             "for each; default: the script's own defaults), as one point of `swarmdeck sweep`")
    parser.add_argument("script_args", nargs="*", metavar="ARGS",
                        help="arguments for the script after `--` (its sys.argv[1:], as `python SCRIPT.py ARGS`); "
                             "the script runs as __main__, so code under `if __name__ == \"__main__\":` runs")


def _run_sandboxed(args: argparse.Namespace) -> int:
    from swarmdeck.console.cli.env import checked_script_env
    from swarmdeck.console.sandbox.confinement import ConfinementUnavailable, JailConfig
    from swarmdeck.console.sandbox.plant import ArenaPlant, with_obstacles
    from swarmdeck.console.sandbox.run import run_sandboxed
    from swarmdeck.core.robot_models import robot_params
    from swarmdeck.devices.arena import Arena
    from swarmdeck.devices.simulator import ArenaConfig

    check_run_arguments(args.robots, args.duration, seed=args.seed)
    config = ArenaConfig(seed=args.seed, obstacles=obstacles_argument(args))
    model = args.robot_model or _script_robot_model(args)

    def make_plant(n, initial, obstacles=None):  # obstacles: the script's own (rps 2.x), solid beside the lab's
        cfg = config if obstacles is None else dataclasses.replace(config, obstacles=with_obstacles(config, obstacles))
        return ArenaPlant(Arena(n, initial_conditions=initial, config=cfg,
                                safety=not (args.no_safety or args.rps_semantics), duration=args.duration,
                                params=robot_params(model)))

    try:
        outcome = run_sandboxed(args.script, make_plant, entry=args.entry, n_robots=args.robots, duration=args.duration, rps=args.rps,
                                argv=_script_args(args), rps_semantics=args.rps_semantics,
                                rps_call_order=args.rps_call_order,
                                robot_model=model, rps_generation=args.rps_generation, params=param_values(args.param),
                                trusted=args.trusted, jail=JailConfig(order=(args.jail,) if args.jail else JailConfig().order,
                                                                     allow_no_cgroup=args.allow_no_cgroup,
                                                                     script_env=checked_script_env(args.script_env)))
    except (ConfinementUnavailable, ValueError) as exc:
        raise UsageError(str(exc)) from exc
    if outcome.log:
        print(outcome.log, end="" if outcome.log.endswith("\n") else "\n")
    for line in outcome.unhardened:
        print(f"swarmdeck run: warning: {line}", file=sys.stderr)
    report = outcome.plant.arena.report() if outcome.plant is not None else None
    if args.json:
        print(json.dumps({"reports": [report.to_dict()] if report else [], "error": outcome.error,
                          "error_line": outcome.error_line, "ended_by": outcome.ended_by,
                          "overruns": outcome.overruns, "cgroup": outcome.cgroup,
                          "unhardened": outcome.unhardened}, indent=2))
    elif report is not None:
        print(report)
    if outcome.error_line:
        raise UsageError(f"the sandboxed script ended, robots were stopped: {outcome.error_line}")
    return 0


def _script_robot_model(args: argparse.Namespace) -> str:
    """The robot model the script expects (the GTernal for an rps 2.x script, else the GRITSBot), read on the trusted
    side from the script's text (the entry file of a directory) before the run — its plant drives that model."""
    from pathlib import Path

    from swarmdeck.core.robot_models import DEFAULT_ROBOT_MODEL
    from swarmdeck.devices.rps.generation import robot_model_for

    path = Path(args.script)
    if path.is_dir():
        path = path / (args.entry or "main.py")
    if args.rps_generation is not None:
        return "gternal" if args.rps_generation == 2 else DEFAULT_ROBOT_MODEL
    try:
        return robot_model_for(path.read_text(encoding="utf-8", errors="replace"))
    except OSError:
        return DEFAULT_ROBOT_MODEL  # run_sandboxed names the unreadable script


def _physical_robots(args: argparse.Namespace) -> tuple[Callable[..., Any], Any]:
    """``--robots-via``: the robots, opened now by the one robots factory
    (:func:`~swarmdeck.console.runtime.hardware.open_robots`), and the ``backend_factory`` handing them
    to the one Arena the script builds."""
    from swarmdeck.console.runtime.hardware import RobotsSpec, open_robots

    if args.robots is None:
        raise UsageError("--robots-via needs --robots N: the robots 0..N-1 to drive")
    try:
        ports = open_robots(RobotsSpec(n_robots=args.robots, robots_via=args.robots_via))
    except (ValueError, OSError) as exc:
        raise UsageError(str(exc)) from None
    handed: list[bool] = []

    def factory(n: int | None, initial: Any, *, config: Any, params: Any) -> tuple[Any, Any]:
        if handed:
            raise ValueError("a run on physical robots drives one Arena (its robots are in use)")
        want = len(initial) if initial is not None else n
        if want is not None and want != args.robots:
            raise ValueError(f"the script asks for {want} robots; --robots-via drives --robots {args.robots}")
        if initial is not None:
            print("swarmdeck run: the physical robots start where they are (the script's initial conditions "
                  "are not driven to)", file=sys.stderr)
        handed.append(True)
        return ports.source, ports.sink

    return factory, ports


def obstacles_argument(args: argparse.Namespace, chargers: bool = False) -> Any:
    """``--obstacles FILE``'s :class:`~swarmdeck.core.obstacles.Obstacles` (None without it), checked inside the
    default arena (and clear of its charger slots with ``chargers``); UsageError naming the file, the key and the
    segment for a file that cannot be used."""
    path = getattr(args, "obstacles", None)
    if path is None:
        return None
    from swarmdeck.console.runtime.config import read_obstacles
    from swarmdeck.core.bounds import DEFAULT_BOUNDS
    from swarmdeck.devices.chargers import ChargerLayout
    from swarmdeck.devices.fleet.routing import check_chargers_clear

    try:
        obstacles = read_obstacles(path)
        if obstacles is not None:
            obstacles.check_inside(DEFAULT_BOUNDS)
            if chargers:
                check_chargers_clear(obstacles, ChargerLayout())
        return obstacles
    except ValueError as exc:
        raise UsageError(f"--obstacles {path}: {exc}" if str(path) not in str(exc) else str(exc)) from None


def _script_args(args: argparse.Namespace) -> list[str]:
    return [str(a) for a in args.script_args or []]


def _capsule_of(args: argparse.Namespace) -> tuple[Any, dict[str, bytes]]:
    """What reproduces this ``swarmdeck run --record`` (a ``capsule.Manifest``) and its files: the script, and the
    ``--obstacles`` file as ``_capsule/obstacles.toml``."""
    from pathlib import Path

    from swarmdeck.console.recording.capsule import manifest_for
    from swarmdeck.console.recording.capsule_zip import CapsuleError, script_files

    try:
        files, entry = script_files(args.script)
        obstacles = None
        if args.obstacles is not None:
            obstacles = "_capsule/obstacles.toml"
            files[obstacles] = Path(args.obstacles).read_bytes()
    except (CapsuleError, OSError) as exc:
        raise UsageError(str(exc)) from None
    run = {"robots": args.robots, "duration": args.duration, "seed": args.seed, "safety": not args.no_safety,
           "params": param_values(args.param),
           "from_docks": bool(args.from_docks), "rps": args.rps, "rps_semantics": bool(args.rps_semantics),
           "rps_call_order": bool(args.rps_call_order), "robot_model": args.robot_model,
           "rps_generation": args.rps_generation, "argv": _script_args(args), "sandbox": False,
           "obstacles": obstacles, "robots_via": args.robots_via is not None}
    return manifest_for("run", files, entry=entry, run=run), files


def _run_capsule(args: argparse.Namespace) -> int:
    """``swarmdeck run run.zip``: check, extract to a temporary folder, re-execute, print the verdict."""
    import tempfile
    from pathlib import Path

    given = [f"--{name.replace('_', '-')}" for name in ("robots", "duration", "seed", "record", "obstacles", "robots_via",
                                                         "robot_model", "rps_generation", "entry", "script_env")
             if getattr(args, name, None) is not None]
    given += [f"--{name.replace('_', '-')}" for name in ("no_safety", "from_docks", "rps_semantics")
              if getattr(args, name, False)]
    if given or args.script_args:
        raise UsageError(f"a capsule runs with the arguments it recorded: drop {' '.join(given) or 'the script arguments'}")

    from swarmdeck.console.recording.capsule_run import reproduce
    from swarmdeck.console.recording.capsule_zip import CapsuleError, open_capsule

    with tempfile.TemporaryDirectory(prefix="swarmdeck-capsule-") as tmp:
        try:
            opened = open_capsule(args.script, Path(tmp) / "capsule")
            verdict = reproduce(opened, tmp, sandbox=args.sandbox)
        except CapsuleError as exc:
            raise UsageError(str(exc)) from None
    print(json.dumps(verdict.to_dict(), indent=2) if args.json else verdict.summary())
    return verdict.exit_code


def main(args: argparse.Namespace) -> int:
    if str(args.script).endswith(".zip"):
        return _run_capsule(args)
    if args.script_env is not None and not args.sandbox:
        raise UsageError("--script-env needs --sandbox (the script environment is the jail's)")
    if args.entry is not None and not args.sandbox:
        raise UsageError("--entry needs --sandbox (a directory of files runs in the sandbox)")
    if args.robots_via is not None and (args.sandbox or args.from_docks):
        raise UsageError(f"--robots-via does not combine with {'--sandbox' if args.sandbox else '--from-docks'}")
    if args.sandbox:
        if args.from_docks:
            raise UsageError("--from-docks does not combine with --sandbox yet")
        if args.record:
            raise UsageError("--record does not combine with --sandbox yet")
        return _run_sandboxed(args)
    factory, ports = _physical_robots(args) if args.robots_via is not None else (None, None)
    recording = None
    if args.record:
        from swarmdeck.console.recording.arena_recording import ArenaRecording

        if args.seed is None:  # the random start is drawn from a recorded seed, so the capsule reproduces it
            import secrets

            args.seed = secrets.randbelow(2**31)
            print(f"swarmdeck run: --seed {args.seed} (drawn for the recording: its capsule reproduces the run)",
                  file=sys.stderr)
        capsule, capsule_files = _capsule_of(args)
        recording = ArenaRecording(args.record, script=args.script, seed=args.seed,
                                   foxglove_channels=args.foxglove_channels, capsule=capsule,
                                   foxglove_entities=args.foxglove_entities,
                                   capsule_files=capsule_files)
    try:
        with params_in_environment(param_values(args.param)):
            result = run_headless(args.script, args, rps=args.rps, from_docks=args.from_docks, argv=_script_args(args),
                                  obstacles=obstacles_argument(args),
                                  rps_semantics=args.rps_semantics, rps_call_order=args.rps_call_order,
                                  robot_model=args.robot_model, rps_generation=args.rps_generation,
                                  on_create=None if recording is None else recording.on_create,
                                  on_step=None if recording is None else recording.on_step, backend_factory=factory)
    finally:
        if ports is not None:
            ports.close()  # robots stopped, link closed
        if recording is not None:
            for line in recording.close():
                print(f"swarmdeck run: {line}", file=sys.stderr)
    if args.json:
        print(json.dumps({"reports": [r.to_dict() for r in result.reports], "error": result.error,
                          "error_line": result.error_line, "notes": result.notes,
                          "interrupted": result.interrupted}, indent=2))
    else:
        for report in result.reports:
            print(report)
        for note in result.notes:
            print(f"note: {note}")
        if isinstance(result.returned, dict):
            for key, value in result.returned.items():
                print(f"{key}: {value}")
    if result.interrupted:
        print("swarmdeck run: interrupted (robots stopped); the report covers the run so far", file=sys.stderr)
        return 130
    raise_if_failed(result)
    return 0


def _one_then_other(first: Callable[[Any], object], then: Callable[[Any], object]) -> Callable[[Any], None]:
    """A per-step callback calling ``first`` and then ``then`` with the same Arena (a caller's ``on_step``
    beside the progress bar)."""
    def both(arena: Any) -> None:
        first(arena)
        then(arena)
    return both


def add_run_arguments(parser: argparse.ArgumentParser, robots: int, duration: float) -> None:
    """--robots, --duration, --seed and --no-safety with the given defaults (an example's)."""
    parser.add_argument("--robots", type=int, default=robots, metavar="N", help=f"number of robots (default {robots})")
    parser.add_argument("--duration", type=float, default=duration, metavar="S", help=f"simulated seconds (default {duration:g})")
    parser.add_argument("--seed", type=int, default=None, help="seed for the random initial conditions")
    parser.add_argument("--no-safety", action="store_true", help="run without the safety barrier")


def check_seed(seed: int | None) -> None:
    """UsageError unless ``--seed`` is None or a non-negative integer (what numpy's generators take)."""
    if seed is not None and seed < 0:
        raise UsageError(f"--seed must be a non-negative integer, got {seed}")


def check_run_arguments(robots: int | None, duration: float | None, min_robots: int = 1, what: str = "",
                        seed: int | None = None) -> None:
    """UsageError unless ``--robots`` is >= ``min_robots``, ``--duration`` a finite number > 0 and
    ``--seed`` non-negative (None: not given)."""
    check_seed(seed)
    if robots is not None and robots < min_robots:
        raise UsageError(f"--robots must be >= {min_robots}{' for ' + what if what else ''}, got {robots}")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise UsageError(f"--duration must be a finite number of seconds > 0, got {duration}")


def run_headless(experiment: Callable[..., Any] | str, args: argparse.Namespace, min_robots: int = 1,
                 what: str = "", **kw: Any) -> Any:
    """Run ``experiment`` (a callable or a script path) with the common arguments; print the reports.

    Returns the :class:`~swarmdeck.devices.runner.RunResult`. Raises UsageError when
    the run cannot start (bad script file, too many robots) or when the experiment raised
    (one line naming the script's line; the reports are printed first, the robots were stopped).
    """
    from swarmdeck.devices.runner import ScriptError, progress_bar, run_experiment

    check_run_arguments(args.robots, args.duration, min_robots, what, args.seed)
    on_step, close = progress_bar(args.duration)
    also = kw.pop("on_step", None)
    if also is not None:
        on_step = also if on_step is None else _one_then_other(also, on_step)
    try:
        result = run_experiment(experiment, n_robots=args.robots, duration=args.duration, seed=args.seed,
                                safety=not args.no_safety, on_step=on_step, **kw)
    except (ScriptError, ValueError) as exc:
        raise UsageError(str(exc)) from exc
    finally:
        close()
    return result


def raise_if_failed(result: Any) -> None:
    """After the reports are printed: a run whose experiment raised is a UsageError (exit 2)."""
    if result.error_line:
        raise UsageError(f"the experiment raised, robots were stopped: {result.error_line}")

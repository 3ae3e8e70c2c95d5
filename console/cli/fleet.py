"""``swarmdeck fleet status|dock|setup POSES.csv|release``: the operator's view of the fleet and its upkeep.

The robots are the arena's (``--robots-via mqtt://…``: GRITSBots or ``swarmdeck robots``) or a
simulated arena (``--simulated N``). ``status --server URL`` asks the lab's portal (``swarmdeck server``,
an operator token) instead: its fleet table, with the robots assigned to the running job. ``dock``, ``setup`` and ``release`` drive them through the
console's control loop and its safety pipeline (:mod:`swarmdeck.console.runtime.fleet_upkeep`).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from swarmdeck.console.cli import UsageError

NAME = "fleet"
HELP = "the fleet between experiments: status (battery, charging, docked), dock, setup POSES.csv, release"
ORDER = 62

ACTIONS = ("status", "dock", "setup", "release")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = (
        "status: one row per robot (battery, charge, charging, docked slot, link, last seen). "
        "dock: robots on the floor (or --ids) back onto free charger slots. "
        "setup POSES.csv: assign charged, healthy robots and drive them to the start poses (x, y, theta per line). "
        "release: after an experiment or an emergency stop, every robot on the floor returns to the chargers "
        "and the arena is ready. Exit codes: 0 done, 1 the maneuver failed (robots stopped, named), 2 bad input.")
    parser.add_argument("action", choices=ACTIONS, help="what to do")
    parser.add_argument("poses", nargs="?", default=None, metavar="POSES.csv",
                        help="setup: the start poses, one 'x, y, theta' line (m, m, rad) per robot")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--robots-via", default=None, metavar="URL",
                       help="the arena's robots over MQTT, e.g. mqtt://127.0.0.1:1883")
    where.add_argument("--server", default=None, metavar="URL",
                       help="status only: the fleet of the lab's portal (swarmdeck server), with the robots "
                            "assigned to the running job; needs an operator token (--token or $SWARMDECK_TOKEN)")
    where.add_argument("--simulated", type=int, default=None, metavar="N",
                       help="a simulated arena of N robots instead (docked at start for status/setup, on the floor "
                            "for dock/release unless --start says otherwise)")
    parser.add_argument("--start", choices=("docked", "random"), default=None,
                        help="--simulated: where the robots start")
    parser.add_argument("--charge", type=float, default=1.0, metavar="Q",
                        help="--simulated: initial state of charge in [0, 1] (default %(default)s)")
    parser.add_argument("--seed", type=int, default=None, help="--simulated: seed of the random start poses")
    parser.add_argument("--ids", default=None, metavar="LIST", help="dock: only these robot ids, e.g. 3,5-7")
    parser.add_argument("--time-limit", type=float, default=None, metavar="S",
                        help="fail (robots stopped) after this many s (default: 60 s + 2 s per robot)")
    parser.add_argument("--wait", type=float, default=3.0, metavar="S",
                        help="--robots-via: s to listen for robots before acting (default %(default)s)")
    parser.add_argument("--token", default=None, help="--server: an operator's access token (default: $SWARMDECK_TOKEN)")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")


def main(args: argparse.Namespace) -> int:
    if args.action == "setup" and args.poses is None:
        raise UsageError("setup needs POSES.csv (one 'x, y, theta' line per robot)")
    if args.action != "setup" and args.poses is not None:
        raise UsageError(f"{args.action} takes no POSES.csv")
    if args.server is not None:
        if args.action != "status":
            raise UsageError(f"{args.action} through --server: the portal's arena sets up and returns its robots "
                             "itself between jobs (use --robots-via on the arena's machine when no server runs)")
        return _server_status(args)
    from swarmdeck.console.runtime import fleet_upkeep as fu  # here: `status --server` stays a thin client
    if args.token is not None:
        raise UsageError("--token goes with --server")
    if args.robots_via is None and args.simulated is None:
        raise UsageError("name the robots: --server URL, --robots-via mqtt://HOST:PORT or --simulated N")
    if args.simulated is not None and args.simulated < 1:
        raise UsageError(f"--simulated must be a number of robots >= 1, got {args.simulated}")
    if not 0.0 <= args.charge <= 1.0:
        raise UsageError(f"--charge must be a state of charge in [0, 1], got {args.charge}")
    if args.time_limit is not None and not (math.isfinite(args.time_limit) and args.time_limit > 0):
        raise UsageError(f"--time-limit must be a positive number of seconds, got {args.time_limit}")
    if not (math.isfinite(args.wait) and args.wait > 0):
        raise UsageError(f"--wait must be a positive number of seconds, got {args.wait}")
    ids = None
    if args.ids is not None:
        if args.action != "dock":
            raise UsageError("--ids applies to dock only")
        from swarmdeck.console.cli.robots import parse_ids

        ids = parse_ids(args.ids)
    goals = None
    if args.action == "setup":
        try:
            goals = fu.read_poses_csv(args.poses)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    config = fu.UpkeepConfig() if args.time_limit is None else fu.UpkeepConfig(time_limit=args.time_limit)
    loop, pace = _open(args)
    try:
        frame = loop.tick()
        if args.action == "status":
            return _print_status(_status(loop, frame), args.json)
        return _act(args, loop, pace, frame, goals, ids, config)
    finally:
        loop.close()


def _open(args: argparse.Namespace) -> tuple[Any, Any]:
    """The control loop on the named robots (paused: nothing moves until an action runs) and its pacer.
    The robots come from the one robots factory (:func:`~swarmdeck.console.runtime.hardware.open_robots`)."""
    import time

    from swarmdeck.console.runtime.hardware import RobotsSpec, open_robots
    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.devices.clock import RealTimePacer

    cfg = LoopConfig(n_robots=args.simulated or 1, behaviour="rendezvous", seed=args.seed)
    if args.simulated is not None:
        start = args.start or ("docked" if args.action in ("status", "setup") else "random")
        spec = RobotsSpec(n_robots=args.simulated, bounds=cfg.bounds, dt=cfg.dt, seed=args.seed,
                          docked=start == "docked", chargers=True, charge=args.charge)
    else:
        spec = RobotsSpec(n_robots=None, bounds=cfg.bounds, dt=cfg.dt, robots_via=args.robots_via,
                          wait_for_poses=args.wait)
    try:
        ports = open_robots(spec)
    except (ValueError, OSError) as exc:
        raise UsageError(str(exc)) from None
    if spec.simulated:
        loop = ControlLoop(cfg, source=ports.source, sink=ports.sink)
        loop.pause()
        return loop, None
    loop = ControlLoop(cfg, source=ports.source, sink=ports.sink, clock=time.monotonic)
    loop.pause()
    return loop, RealTimePacer(cfg.dt).wait


def _server_status(args: argparse.Namespace) -> int:
    """``status --server URL``: the portal's fleet table (docked, charging, assigned to job X, away)."""
    from swarmdeck.console.cli._client import client, fail
    from swarmdeck.console.portal.client import ClientError

    try:
        with client(args) as c:
            arena = c.arena()
    except ClientError as exc:
        return fail("fleet", exc, args.json)
    fleet = arena.get("fleet") or {"robots": [], "ready": False, "docked": 0, "size": 0, "error": None}
    if args.json:
        print(json.dumps({**fleet, "stopped": arena.get("stopped"), "needs_operator": arena.get("needs_operator")},
                         indent=1))
        return 0
    print(f"{'robot':>5}  {'state':<18}  {'charge':>6}  {'docked':>9}")
    for r in fleet["robots"]:
        state = r["state"] + (f" to job {r['job']}" if r.get("job") is not None else "")
        charge = f"{r['charge']:.0%}" if r.get("charge") is not None else "–"
        docked = f"slot {r['slot']}" if r.get("slot") is not None else ("–" if r["state"] == "missing" else "floor")
        print(f"{r['id']:>5}  {state:<18}  {charge:>6}  {docked:>9}")
    ready = "arena ready" if fleet["ready"] else "arena NOT ready"
    print(f"{fleet['docked']}/{fleet['size']} docked · {ready}" + (f" · {fleet['error']}" if fleet.get("error") else ""))
    if arena.get("needs_operator"):
        print(f"NEEDS AN OPERATOR: {arena['needs_operator']}")
    return 0


def _status(loop: Any, frame: Any) -> list[dict[str, Any]]:
    """One JSON-able row per robot of ``frame``: battery, charge, charging, docked slot, link, ages."""
    from swarmdeck.console.runtime.batteries import battery_levels
    from swarmdeck.core.ports import ReportsRobotHealth
    from swarmdeck.devices.chargers import ChargerLayout

    q, _ = battery_levels(frame.battery, frame.charging)
    slot = ChargerLayout(bounds=frame.bounds).docked_slot(frame.poses)
    table = loop.sink.robot_health() if isinstance(loop.sink, ReportsRobotHealth) else {}
    rows = []
    for k, rid in enumerate(frame.ids.tolist()):  # a table for people, once
        h = table.get(str(rid), {})
        volts = float(frame.battery[k])
        rows.append({
            "id": rid, "x": float(frame.poses[k, 0]), "y": float(frame.poses[k, 1]), "theta": float(frame.poses[k, 2]),
            "battery_voltage": volts if math.isfinite(volts) else None,
            "charge": float(q[k]) if math.isfinite(q[k]) else None,
            "charging": bool(frame.charging[k]), "docked_slot": int(slot[k]) if slot[k] >= 0 else None,
            "link": h.get("link", "ok" if frame.seen[k] else "stale"),
            "last_seen_s": h.get("status_age") if h else (0.0 if frame.seen[k] else None),
        })
    return rows


def _print_status(rows: list[dict[str, Any]], as_json: bool) -> int:
    if as_json:
        print(json.dumps({"robots": rows, "docked": sum(r["docked_slot"] is not None for r in rows),
                          "ready": all(r["docked_slot"] is not None for r in rows)}, indent=1))
        return 0
    print(f"{'robot':>5}  {'battery':>8}  {'charge':>6}  {'charging':>8}  {'docked':>9}  {'link':>8}  {'last seen':>9}")
    for r in rows:
        volts = f"{r['battery_voltage']:.2f} V" if r["battery_voltage"] is not None else "NaN"
        charge = f"{r['charge']:.0%}" if r["charge"] is not None else "–"
        docked = f"slot {r['docked_slot']}" if r["docked_slot"] is not None else "floor"
        seen = f"{r['last_seen_s']:.1f} s" if isinstance(r["last_seen_s"], (int, float)) else "never"
        print(f"{r['id']:>5}  {volts:>8}  {charge:>6}  {'yes' if r['charging'] else 'no':>8}  {docked:>9}  "
              f"{r['link']:>8}  {seen:>9}")
    n_docked = sum(r["docked_slot"] is not None for r in rows)
    print(f"{n_docked}/{len(rows)} docked" + (" · ready" if n_docked == len(rows) else ""))
    return 0


def _act(args: argparse.Namespace, loop: Any, pace: Any, frame: Any, goals: Any, ids: Any, config: Any) -> int:
    from swarmdeck.console.runtime import fleet_upkeep as fu
    from swarmdeck.devices.chargers import ChargerLayout

    chargers = ChargerLayout(bounds=frame.bounds)
    view = fu.FleetView.of(frame, fu.status_ages(loop.sink, frame.ids, frame.is_virtual))
    try:
        if args.action == "setup":
            maneuver = fu.set_up(view, goals, frame.bounds, chargers, loop.robot, config.fleet.safety_distance, config,
                                 obstacles=frame.obstacles)
        else:
            maneuver = fu.return_to_chargers(view, frame.bounds, chargers, loop.robot, config, ids=ids,
                                             obstacles=frame.obstacles)
    except ValueError as exc:
        raise UsageError(f"{args.action}: {exc}") from None
    result = fu.run_maneuver(loop, maneuver, pace)
    out = {"action": args.action, **result.to_dict()}
    if args.action == "setup":
        out["assignment"] = {str(k): rid for k, rid in enumerate(result.robots)}
    if args.action == "release":
        last = loop.latest
        import numpy as np  # here: `fleet status --server` (a thin client) never loads it
        out["ready"] = bool(np.all(chargers.docked_slot(last.poses) >= 0)) if last is not None else False
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        print(result.message)
        if args.action == "setup" and result.ok:
            print("experiment robot -> robot id: " + ", ".join(f"{k} -> {rid}" for k, rid in enumerate(result.robots)))
        if result.ok:
            print(f"collisions: {result.collisions}; deadlock escapes: {result.escapes}")
        if args.action == "release":
            print("arena ready: every robot docked" if out["ready"] else "arena NOT ready: robots left on the floor")
    if not result.ok:
        print(f"swarmdeck fleet: {args.action} failed: {result.message}", file=sys.stderr)
        return 1
    return 0

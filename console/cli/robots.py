"""``swarmdeck robots``: a simulated GRITSBot X fleet on an MQTT broker, in its own process.

Run it next to ``swarmdeck console --robots-via mqtt://HOST:PORT``; several
fleets with distinct ids (``--ids``) on several machines can share one broker
(give them the same ``--seed`` and ``--layout`` so their robots do not start on
top of each other).
"""
from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time

import numpy as np

from swarmdeck.console.cli import UsageError
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.devices.initial_conditions import random_initial_poses

NAME = "robots"
HELP = "run a simulated GRITSBot fleet that takes commands over MQTT (like the robots' firmware)"
ORDER = 60


def parse_ids(text: str) -> np.ndarray:
    """``"0-11,20,22"`` → sorted distinct ids; UsageError on anything else."""
    out: list[int] = []
    for part in text.split(","):
        part = part.strip()
        try:
            if "-" in part:
                a, b = part.split("-", 1)
                lo, hi = int(a), int(b)
                if lo > hi:
                    raise ValueError
                out.extend(range(lo, hi + 1))
            else:
                out.append(int(part))
        except ValueError:
            raise UsageError(f"--ids: {part!r} is not an id or a range like 0-11 (expected e.g. 0-11,20)") from None
    arr = np.asarray(out, dtype=np.intp)
    if len(arr) == 0 or np.any(arr < 0):
        raise UsageError(f"--ids must name non-negative robot ids, got {text!r}")
    if len(np.unique(arr)) != len(arr):
        raise UsageError(f"--ids names some robot twice: {text!r}")
    return np.sort(arr)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--broker", default="mqtt://127.0.0.1:1883",
                        help="broker URL mqtt://[user:pass@]HOST:PORT[/prefix/] or mqtts://… for TLS (default %(default)s)")
    parser.add_argument("--robots", type=int, default=12, help="number of robots, ids 0..N-1 (default %(default)s)")
    parser.add_argument("--ids", default=None, help="explicit robot ids, e.g. 12-23 (overrides --robots)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the random start poses (default %(default)s)")
    parser.add_argument("--layout", type=int, default=None,
                        help="place robots as row <id> of a layout for this many robots (share it between fleets)")
    parser.add_argument("--bounds", type=float, nargs=4, default=DEFAULT_BOUNDS,
                        metavar=("XMIN", "XMAX", "YMIN", "YMAX"), help="arena rectangle, m (default: Robotarium)")
    parser.add_argument("--qos", type=int, choices=(0, 1), default=0, help="MQTT QoS (default %(default)s)")
    parser.add_argument("--mqtt-version", choices=("3.1.1", "5"), default="3.1.1", help="MQTT protocol version")
    parser.add_argument("--prefix", default=None, help="topic prefix, e.g. lab2/ (default: from the URL path, else none)")
    parser.add_argument("--username", default=None, help="broker user name")
    parser.add_argument("--password-env", default="SWARMDECK_MQTT_PASSWORD",
                        help="environment variable holding the broker password (default %(default)s)")
    parser.add_argument("--ca-certs", default=None, help="CA bundle for TLS")
    parser.add_argument("--certfile", default=None, help="client certificate for TLS")
    parser.add_argument("--keyfile", default=None, help="client key for TLS")
    parser.add_argument("--timeout", type=float, default=0.5, help="firmware brake after this many s without commands")
    parser.add_argument("--pose-rate", type=float, default=30.0, help="ground-truth pose messages per second")
    parser.add_argument("--pose-decimals", type=int, default=3, help="rounding of published poses (tracker: 2, Vicon: 3)")
    parser.add_argument("--battery-ah", type=float, default=1.0, help="battery capacity, Ah")
    parser.add_argument("--charge", type=float, default=1.0, metavar="Q",
                        help="initial state of charge in [0, 1] (default %(default)s)")
    parser.add_argument("--start", choices=("random", "docked"), default="random",
                        help="start poses: random on the floor (default) or docked on the charging strips "
                             "(robot id k on slot k)")
    parser.add_argument("--no-chargers", action="store_true",
                        help="no charging strips: robots only drain (default: strips along the walls; robots "
                             "docked on a slot charge and report charge_status true)")
    parser.add_argument("--duration", type=float, default=None, help="exit after this many seconds (default: run until stopped)")
    parser.add_argument("--trace", default=None, help="append '<recv time> <id> <v> <w>' per received command to this file")
    parser.add_argument("--name", default=None, help="node name in status messages (default fleet-<host>-<pid>)")
    parser.add_argument("--quiet", action="store_true", help="no periodic status line")


def main(args: argparse.Namespace) -> int:
    from swarmdeck.devices.battery import BatteryParams
    from swarmdeck.devices.chargers import ChargerLayout
    from swarmdeck.devices.net.firmware import FirmwareParams
    from swarmdeck.devices.net.fleet import FleetNode
    from swarmdeck.devices.net.mqtt_config import parse_broker_url

    if args.ids is not None:
        ids = parse_ids(args.ids)
    else:
        if args.robots < 1:
            raise UsageError(f"--robots must be >= 1, got {args.robots}")
        ids = np.arange(args.robots, dtype=np.intp)
    layout = args.layout if args.layout is not None else int(ids.max()) + 1
    if layout <= ids.max():
        raise UsageError(f"--layout {layout} is too small for robot id {int(ids.max())} (needs > the largest id)")
    if not (np.isfinite(args.pose_rate) and args.pose_rate > 0):
        raise UsageError(f"--pose-rate must be a positive number of messages per second, got {args.pose_rate}")
    if args.seed is not None and args.seed < 0:
        raise UsageError(f"--seed must be a non-negative integer, got {args.seed}")
    if args.duration is not None and not (np.isfinite(args.duration) and args.duration > 0):
        raise UsageError(f"--duration must be a finite number of seconds > 0, got {args.duration}")
    if not 0.0 <= args.charge <= 1.0:
        raise UsageError(f"--charge must be a state of charge in [0, 1], got {args.charge}")
    if args.start == "docked" and args.no_chargers:
        raise UsageError("--start docked needs the charging strips (drop --no-chargers)")
    try:
        cfg = parse_broker_url(
            args.broker, qos=args.qos, protocol=args.mqtt_version, prefix=args.prefix, username=args.username,
            password=os.environ.get(args.password_env) if args.username else None,
            ca_certs=args.ca_certs, certfile=args.certfile, keyfile=args.keyfile,
        )
        firmware = FirmwareParams(command_timeout=args.timeout, pose_period=1.0 / args.pose_rate,
                                  pose_decimals=args.pose_decimals)
        battery = BatteryParams(capacity_ah=args.battery_ah)
        chargers = None if args.no_chargers else ChargerLayout(bounds=Bounds(*args.bounds))
        if args.start == "docked":
            docks = chargers.dock_poses()
            if ids.max() >= len(docks):
                raise ValueError(f"--start docked: robot id {int(ids.max())} has no charger slot (the strips have "
                                 f"{len(docks)} slots, ids 0..{len(docks) - 1})")
            poses = docks[ids]
        else:
            poses = random_initial_poses(layout, Bounds(*args.bounds), rng=args.seed)[ids]
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    try:
        trace = open(args.trace, "a", buffering=1 << 16) if args.trace else None
    except OSError as exc:
        raise UsageError(f"--trace {args.trace}: cannot open for appending: {exc.strerror or exc}") from None
    try:
        node = FleetNode(cfg, ids, poses, firmware=firmware, battery=battery, name=args.name, trace=trace,
                         chargers=chargers, charge=args.charge)
    except ValueError as exc:  # e.g. unreadable TLS files
        if trace is not None:
            trace.close()
        raise UsageError(str(exc)) from None
    stop = threading.Event()

    def on_signal(signum: int, frame: object) -> None:
        stop.set()

    old = signal.signal(signal.SIGTERM, on_signal)
    node.start()
    print(f"swarmdeck robots: {len(ids)} simulated GRITSBots (ids {ids.min()}..{ids.max()}) as {node.name!r} "
          f"on {cfg.url} (topics {cfg.command_topic(int(ids[0]))}, {cfg.pose_topic}); Ctrl-C stops", flush=True)
    t_end = None if args.duration is None else time.monotonic() + args.duration
    try:
        last_print = 0.0
        while not stop.is_set():
            if t_end is not None and time.monotonic() >= t_end:
                break
            stop.wait(0.2)
            now = time.monotonic()
            if not args.quiet and now - last_print >= 5.0:
                last_print = now
                snap = node.snapshot()
                moving = int(np.count_nonzero((snap["v"] != 0) | (snap["w"] != 0)))
                c = node.counters.snapshot()
                print(f"[robots] {node.link.state}; {moving}/{len(ids)} moving; commands "
                      f"{int(snap['commands_received'].sum())}; brakes {int(snap['timeouts'].sum())}; "
                      f"battery min {node.state.battery_voltage().min():.2f} V, "
                      f"{int(node.state.charging().sum())} charging"
                      + (f"; problems {c}" if any(k not in ('reconnects',) for k in c) else ""), flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        node.stop()
        signal.signal(signal.SIGTERM, old)
        if trace is not None:
            trace.close()
        err = node.counters.last_error
        if err:
            print(f"swarmdeck robots: last problem: {err}", file=sys.stderr)
    return 0

"""``swarmdeck server``: the lab's remote-access service (HTTP API, verification workers, arena runner)."""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from typing import Any

from swarmdeck.console.cli import UsageError
from swarmdeck.core.constants import CONTROL_PERIOD, SAFETY_DISTANCE

NAME = "server"
HELP = "start the lab's remote-access service: accounts, submissions, verification, the arena runner, results"
ORDER = 70
DEFAULT_DATA = "swarmdeck-data"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = ("Add accounts with `swarmdeck users add NAME --role researcher|operator --data DIR`. "
                     "API documentation: http://HOST:PORT/docs (served by the server itself). The data folder is "
                     "0700 and every file the server writes 0600. Run it behind the lab's HTTPS proxy; pass "
                     "--trust-proxy with the proxy's address so that sign-in limits key on the real clients.")
    parser.add_argument("--data", default=DEFAULT_DATA, metavar="DIR",
                        help=f"data folder: database and every job's files (default ./{DEFAULT_DATA})")
    parser.add_argument("--host", default="127.0.0.1", help="interface to bind (default 127.0.0.1: this machine only)")
    parser.add_argument("--port", type=int, default=8000, help="TCP port (default 8000; 0 picks a free one)")
    parser.add_argument("--robots", type=int, default=12, metavar="N",
                        help="robots the arena has, docked on its charging strips at start (at most one per charger "
                             "slot, 50): simulated ones, or the MQTT fleet's ids 0..N-1 (default 12). Each job gets "
                             "charged robots set up at its start poses; afterwards they return to the chargers")
    parser.add_argument("--arena", action="append", default=[], metavar="NAME=SPEC",
                        help="an arena behind this portal; repeat for several (one queue, one set of accounts, one "
                             "operator page). SPEC: sim[,robots=N][,fast] (simulated, in this process), "
                             "mqtt://HOST:PORT[,robots=N] (GRITSBots), remote[,robots=N][,kind=physical|simulated] "
                             "(a `swarmdeck runner --portal URL --arena NAME` on another machine), slots=K (jobs "
                             "at once) and regions=COLSxROWS|auto:COLSxROWS|FILE.toml (sim: its floor divided, one job per region at "
                             "once; the operator page stops one region). E.g. --arena floor=sim,robots=50 --arena annex=remote,robots=12,"
                             "kind=physical. Without --arena: one arena from --robots/--robots-via/--fast. Jobs "
                             "choose with the manifest's \"arena\" and \"needs\" (physical|simulated|either)")
    parser.add_argument("--robots-via", default=None, metavar="URL",
                        help="drive GRITSBots over MQTT instead of simulating them, e.g. mqtt://127.0.0.1:1883")
    parser.add_argument("--obstacles", default=None, metavar="FILE",
                        help="the arena's line-segment obstacles: a TOML file with [arena] obstacles = [...] (as in the "
                             "console's --config); in verification, the jobs' barrier, the set-up and return, the live view")
    parser.add_argument("--sensors", action="store_true",
                        help="record the robots' sensors in every job's Frames (Robotarium 2.0's seven ToF distance "
                             "sensors, encoders, IMU, LEDs): in the recording, the live view, the video and the replay")
    parser.add_argument("--regions", default=None, metavar="LAYOUT",
                        help="divide the simulated floor into regions and run one job per region at once: a TOML "
                             "file with a [regions] table or COLSxROWS, e.g. 2x2, or auto:COLSxROWS (regions allocated per job: "
                             "each job gets the smallest of the floor's guillotine cuts down to that grid that holds "
                             "its robots; see `swarmdeck regions`); --robots "
                             "robots are parked, shared out between the regions; with --arena: divides the one simulated arena "
                             "given (or write regions= in its SPEC)")
    parser.add_argument("--fast", action="store_true",
                        help="simulated arena: run jobs, and the robots' set-up and return, as fast as they compute instead of "
                             "in real time (tests, benchmarks)")
    parser.add_argument("--workers", type=int, default=None, metavar="W",
                        help="local verification worker processes (default: number of cores)")
    parser.add_argument("--ray", default=None, metavar="ADDRESS",
                        help="verify on a Ray cluster ('auto', 'local' or ray://HOST:PORT); needs swarmdeck[ray]")
    parser.add_argument("--verify-concurrent", type=int, default=2, metavar="J",
                        help="jobs verified at once on those workers (default 2: the next job's runs use the cores "
                             "while a job's real-time paced run waits for the clock)")
    parser.add_argument("--verify-runs", type=int, default=4, metavar="K",
                        help="verification runs per job, each without and with the barrier (default 4)")
    parser.add_argument("--verify-epsilon", type=float, default=None, metavar="EPS",
                        help="a job may bypass the barrier only if its report's upper bound on P(contact per run) "
                             "(Clopper-Pearson from the raw runs) is at most EPS; 0.01 at 95 %% confidence needs "
                             "--verify-runs 299 (default: the bound is stated, not required)")
    parser.add_argument("--verify-confidence", type=float, default=0.95, metavar="C",
                        help="confidence of that bound, in (0, 1) (default 0.95)")
    parser.add_argument("--verify-falsify-budget", type=int, default=0, metavar="N",
                        help="per job, up to N more verification runs (no barrier) searching the set-up tolerance and "
                             "the tracking noise for the run closest to a contact; the report gives the worst case "
                             "beside the bound (never in it), its recording is the job's worst-case.mcap, and a "
                             "contact found refuses the bypass (default 0: no search)")
    parser.add_argument("--max-duration", type=float, default=600.0, metavar="S",
                        help="longest experiment a researcher may declare, s (default 600)")
    parser.add_argument("--max-upload", type=int, default=4 << 20, metavar="BYTES",
                        help="largest upload accepted, bytes (default 4 MiB)")
    parser.add_argument("--grace", type=float, default=15.0, metavar="S",
                        help="a run's time limit is its declared duration plus S seconds (default 15)")
    parser.add_argument("--tick-budget", type=float, default=None, metavar="S",
                        help="real-time arena: a script's commands for a tick are due within S seconds of its poses, "
                             "else the robots stop for that tick; 1 s of late ticks in a row ends the run (default: "
                             f"one control period, {CONTROL_PERIOD:g} s). Verification and --fast allow 1 s per tick")
    parser.add_argument("--guard-distance", type=float, default=0.15, metavar="M",
                        help="during a barrier bypass an operator approved, the barrier comes back the first time two "
                             "robots' look-ahead points would come closer than M metres (default 0.15: between contact "
                             f"and the barrier's {SAFETY_DISTANCE:g})")
    parser.add_argument("--guard-intervention", type=float, default=0.1, metavar="MS",
                        help="... or the barrier would have changed a command by more than MS m/s (default 0.1)")
    parser.add_argument("--seed", type=int, default=None, help="seed of the simulated arena's initial poses")
    parser.add_argument("--trusted", action="store_true",
                        help="run scripts unconfined where this machine cannot confine them (bubblewrap missing)")
    parser.add_argument("--allow-no-cgroup", action="store_true",
                        help="run scripts even where no cgroup can be created per run (not root, no memory/pids "
                             "controller): then only per-process limits bound a run's memory, processes and CPU")
    from swarmdeck.console.cli.env import add_script_env_argument

    add_script_env_argument(parser)
    parser.add_argument("--console-port", type=int, default=None, metavar="P",
                        help="also show the running job in the operator's viser view on port P (on --host); with "
                             "--projector it has the projector's folder (layers, brightness, blackout)")
    parser.add_argument("--projector", nargs="?", type=int, const=8090, default=None, metavar="PORT",
                        help="also serve the overhead projector's page for the arena on http://HOST:PORT/projector "
                             "(default port 8090; `chromium --kiosk --app=URL` on the projector's screen)")
    parser.add_argument("--projector-calibration", default=None, metavar="FILE",
                        help="the projector's homography from `swarmdeck calibrate projector` (default "
                             "projector.json if it exists)")
    note = parser.add_argument_group("notifications (researchers set their webhook/e-mail: PUT /api/me/notifications)")
    note.add_argument("--smtp", default=None, metavar="HOST:PORT",
                      help="send e-mail notifications (a job verified, started, ended, rejected) through this SMTP "
                           "server (default: none; webhooks work without it)")
    note.add_argument("--smtp-from", default="swarmdeck@localhost", metavar="ADDR",
                      help="the notifications' sender address (default swarmdeck@localhost)")
    note.add_argument("--smtp-starttls", action="store_true", help="use STARTTLS with the SMTP server")
    quota = parser.add_argument_group("per-researcher limits (0: no limit; operators are not limited)")
    quota.add_argument("--max-jobs", type=int, default=25, metavar="N",
                       help="jobs a researcher may have not yet finished (queued … running); the next submission "
                            "gets 429 naming the limit (default 25)")
    quota.add_argument("--verify-cpu", type=float, default=4 * 3600.0, metavar="S",
                       help="verification CPU seconds a researcher's jobs may use in any 24 h before new submissions "
                            "get 429 (default 14400, 4 CPU hours)")
    quota.add_argument("--disk-quota", type=float, default=2000.0, metavar="MB",
                       help="MB a researcher's jobs' files may take before new submissions get 403 (default 2000)")
    quota.add_argument("--retain-days", type=float, default=None, metavar="D",
                       help="delete the files of jobs that ended more than D days ago (checked hourly; the job's "
                            "row stays, marked; default: keep them)")
    net = parser.add_argument_group("connections")
    net.add_argument("--trust-proxy", action="append", default=[], metavar="ADDR",
                     help="believe X-Forwarded-For/-Proto from this address (your reverse proxy, e.g. 127.0.0.1); "
                          "repeat for several (default: from nobody: the peer's address is the client's)")
    net.add_argument("--max-connections", type=int, default=200, metavar="N",
                     help="connections at once; with N open, a new request gets 503 (default 200)")
    net.add_argument("--header-timeout", type=float, default=10.0, metavar="S",
                     help="a request's line and headers must arrive within S s, else 408 and the connection is "
                          "closed (default 10)")
    net.add_argument("--body-timeout", type=float, default=120.0, metavar="S",
                     help="a request's body must arrive within S s of its headers, else 408 and close (default 120)")
    net.add_argument("--keep-alive", type=float, default=5.0, metavar="S",
                     help="close an idle kept-alive connection after S s (default 5)")
    parser.add_argument("--log-level", default="warning", choices=("critical", "error", "warning", "info", "debug"),
                        help="uvicorn's log level (default warning)")


def check_arguments(args: argparse.Namespace) -> None:
    if not 0 <= args.port <= 65535:
        raise UsageError(f"--port must be in [0, 65535], got {args.port}")
    if args.robots < 1:
        raise UsageError(f"--robots must be >= 1, got {args.robots}")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    if args.verify_runs < 1:
        raise UsageError(f"--verify-runs must be >= 1, got {args.verify_runs}")
    if args.verify_concurrent < 1:
        raise UsageError(f"--verify-concurrent must be >= 1, got {args.verify_concurrent}")
    try:
        from swarmdeck.console.sandbox.guarantee import Guarantee

        Guarantee(1, 0, args.verify_confidence, args.verify_epsilon)
    except ValueError as exc:
        raise UsageError(f"--verify-epsilon/--verify-confidence: {exc}") from None
    if args.verify_falsify_budget < 0:
        raise UsageError(f"--verify-falsify-budget must be >= 0, got {args.verify_falsify_budget}")
    if not args.max_duration > 0:
        raise UsageError(f"--max-duration must be > 0 s, got {args.max_duration}")
    if args.max_upload < 1024:
        raise UsageError(f"--max-upload must be at least 1024 bytes, got {args.max_upload}")
    if not args.grace > 0:
        raise UsageError(f"--grace must be > 0 s, got {args.grace}")
    if args.tick_budget is not None and not 0 < args.tick_budget <= 10:
        raise UsageError(f"--tick-budget must be in (0, 10] s, got {args.tick_budget}")
    if not 0.05 <= args.guard_distance <= SAFETY_DISTANCE:
        raise UsageError(f"--guard-distance must be in [0.05, {SAFETY_DISTANCE:g}] m (at most the barrier's D_s), "
                         f"got {args.guard_distance}")
    if not 0 < args.guard_intervention <= 1:
        raise UsageError(f"--guard-intervention must be in (0, 1] m/s, got {args.guard_intervention}")
    if args.console_port is not None and not 0 <= args.console_port <= 65535:
        raise UsageError(f"--console-port must be in [0, 65535], got {args.console_port}")
    _projector_calibration(args)  # checked before anything opens; loaded again where it is used
    for flag, value in (("--max-jobs", args.max_jobs), ("--verify-cpu", args.verify_cpu),
                        ("--disk-quota", args.disk_quota)):
        if not value >= 0:
            raise UsageError(f"{flag} must be >= 0 (0: no limit), got {value}")
    if args.retain_days is not None and not args.retain_days > 0:
        raise UsageError(f"--retain-days must be > 0, got {args.retain_days}")
    if args.max_connections < 2:
        raise UsageError(f"--max-connections must be >= 2, got {args.max_connections}")
    for flag, value in (("--header-timeout", args.header_timeout), ("--body-timeout", args.body_timeout),
                        ("--keep-alive", args.keep_alive)):
        if not 0 < value <= 3600:
            raise UsageError(f"{flag} must be in (0, 3600] s, got {value}")
    import ipaddress

    for addr in args.trust_proxy:
        try:
            ipaddress.ip_network(addr, strict=False)
        except ValueError:
            raise UsageError(f"--trust-proxy: {addr!r} is not an IP address or network") from None
    if args.fast and args.robots_via:
        raise UsageError("--fast is for the simulated arena: networked robots run in real time")
    if args.regions is not None and args.robots_via:
        raise UsageError("--regions runs on the simulated floor for now: it does not combine with --robots-via")
    if args.arena:
        from swarmdeck.console.portal.arenas import check_unique, parse_arena_spec

        try:
            specs = [parse_arena_spec(a) for a in args.arena]
            check_unique(specs)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        if args.robots_via or args.fast or args.robots != 12:
            raise UsageError("--arena describes each arena's robots: leave out --robots, --robots-via and --fast")
        if args.regions is not None:
            plain = [s for s in specs if not s.remote and s.robots_via is None and s.regions is None]
            if len(plain) != 1:
                raise UsageError("--regions with --arena divides the one simulated arena's floor; with several, "
                                 "give each its own: --arena NAME=sim,robots=N,regions=2x2")
            specs = [replace(s, regions=args.regions) if s is plain[0] else s for s in specs]
        args.arena_specs = tuple(specs)
    else:
        args.arena_specs = ()
    if args.smtp is not None:
        from swarmdeck.console.portal.notify import parse_smtp

        try:
            args.smtp_host = parse_smtp(args.smtp)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    if args.robots_via is not None:
        from swarmdeck.devices.net.mqtt_config import parse_broker_url

        try:
            parse_broker_url(args.robots_via)
        except ValueError as exc:
            raise UsageError(f"--robots-via: {exc}") from None


def _region_specs(specs: tuple[Any, ...]) -> tuple[tuple[Any, ...], dict[str, Any]]:
    """The arenas with their floors divided (``regions=``) planned as one slot per region
    (:func:`~swarmdeck.console.portal.region_runner.region_arena`), and their layouts by arena name."""
    from swarmdeck.console.cli.regions import load_layout
    from swarmdeck.console.portal.region_runner import region_arena

    out, layouts = [], {}
    for spec in specs:
        if spec.regions is None:
            out.append(spec)
            continue
        layout = load_layout(spec.regions)  # UsageError naming a bad layout
        try:
            out.append(region_arena(spec, layout))
        except ValueError as exc:
            raise UsageError(f"--arena {spec.name}: regions={spec.regions}: {exc}") from None
        layouts[spec.name] = layout
    return tuple(out), layouts


def _region_runner(service: Any, settings: Any, layout: Any, live: Any) -> Any:
    """An arena whose simulated floor is divided into regions: its ``settings.fleet`` robots parked, shared out
    between them."""
    from swarmdeck.console.portal.region_runner import RegionRunner, share_robots

    try:
        return RegionRunner(service, settings, layout, share_robots(layout, settings.fleet), live)
    except ValueError as exc:
        service.close()
        raise UsageError(f"--arena {settings.name}: {exc}") from None


def main(args: argparse.Namespace) -> int:
    check_arguments(args)
    from swarmdeck.console.cli.env import checked_script_env
    from swarmdeck.console.portal.app import HttpSettings, bind, create_app, uvicorn_server
    from swarmdeck.console.portal.db import SchemaError
    from swarmdeck.console.portal.livefeed import LiveFeed
    from swarmdeck.console.portal.quotas import Quotas
    from swarmdeck.console.portal.retention import RetentionSweeper
    from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
    from swarmdeck.console.portal.service import PortalConfig, PortalService
    from swarmdeck.console.portal.submission import Limits
    from swarmdeck.console.portal.workers import VerificationWorkers, make_executor
    from swarmdeck.console.sandbox.confinement import JailConfig, describe, probe
    from swarmdeck.devices.chargers import ChargerLayout

    reason = probe(JailConfig(allow_no_cgroup=args.allow_no_cgroup))
    if reason is not None and not args.trusted:
        raise UsageError(f"cannot confine untrusted code on this machine: {reason}; install bubblewrap "
                         "or pass --trusted")
    from swarmdeck.console.cli.run import obstacles_argument

    obstacles = obstacles_argument(args, chargers=True)  # before anything is opened: a bad file is a usage error
    fleet = min(args.robots, ChargerLayout().n_slots)
    if fleet < args.robots:
        raise UsageError(f"--robots {args.robots}: at most {fleet} robots, one per slot of the arena's charging strips")
    for spec in args.arena_specs:
        if not spec.remote and spec.robots > ChargerLayout().n_slots:
            raise UsageError(f"--arena {spec.name}: at most {ChargerLayout().n_slots} robots, one per charger slot")
    specs = args.arena_specs
    if not specs and args.regions is not None:  # the one arena, its floor divided
        from swarmdeck.console.portal.arenas import DEFAULT_ARENA, ArenaSpec

        specs = (ArenaSpec(DEFAULT_ARENA, robots=fleet, fast=args.fast, regions=args.regions),)
    specs, layouts = _region_specs(specs)
    if specs:
        fleet = max(s.largest for s in specs)  # the most any job may ask for; each arena checks its own
    from swarmdeck.console.portal.notify import SmtpSettings

    smtp = None if args.smtp is None else SmtpSettings(args.smtp_host[0], args.smtp_host[1], sender=args.smtp_from,
                                                       starttls=args.smtp_starttls)
    config = PortalConfig(data=args.data, arenas=specs, smtp=smtp,
                          limits=Limits(fleet=fleet, max_duration=args.max_duration,
                                                        max_upload_bytes=args.max_upload),
                          verify_runs=args.verify_runs, verify_epsilon=args.verify_epsilon,
                          verify_confidence=args.verify_confidence,
                          verify_falsify_budget=args.verify_falsify_budget, grace_s=args.grace, trusted=args.trusted,
                          allow_no_cgroup=args.allow_no_cgroup, script_env=checked_script_env(args.script_env),
                          arena_tick_budget_s=args.tick_budget,
                          quotas=Quotas(max_unfinished_jobs=args.max_jobs or None,
                                        verify_cpu_s_per_day=args.verify_cpu or None,
                                        results_bytes=int(args.disk_quota * 1e6) or None),
                          retain_days=args.retain_days)
    http = HttpSettings(max_connections=args.max_connections, header_timeout_s=args.header_timeout,
                        body_timeout_s=args.body_timeout, keep_alive_s=args.keep_alive,
                        trust_proxy=tuple(args.trust_proxy))
    try:
        executor = make_executor(args.workers, args.ray)
    except (ValueError, RuntimeError) as exc:
        raise UsageError(str(exc)) from None
    try:
        sock = bind(args.host, args.port)
    except OSError as exc:
        raise UsageError(f"cannot serve on {args.host}:{args.port}: {exc.strerror or exc}") from None
    import os

    from swarmdeck.console.portal.files import UMASK

    caller_umask = os.umask(UMASK)  # every file the server (its workers, the exports) writes is 0600, every folder 0700
    try:
        service = PortalService(config)
    except (SchemaError, OSError) as exc:
        sock.close()
        os.umask(caller_umask)  # a refused start leaves the caller's process as it found it
        raise UsageError(f"cannot open the data folder {args.data!r}: {exc}") from None
    import sqlite3

    live = LiveFeed()
    from swarmdeck.safety.guard import GuardConfig

    guard = GuardConfig(guard_distance=args.guard_distance, max_intervention=args.guard_intervention)
    runners = []
    for spec in (specs if args.arena_specs else ()):
        settings = ArenaSettings(robots_via=spec.robots_via, fleet=spec.robots, fast=spec.fast, seed=args.seed,
                                 guard=guard, name=spec.name, sensors=args.sensors)
        if spec.name in layouts:
            runners.append(_region_runner(service, settings, layouts[spec.name], live))
        elif not spec.remote:
            runners.append(ArenaRunner(service, settings, live))
    if not args.arena_specs:
        settings = ArenaSettings(robots_via=args.robots_via, fleet=fleet, fast=args.fast, seed=args.seed,
                                 guard=guard, obstacles=obstacles, sensors=args.sensors)
        runners.append(ArenaRunner(service, settings, live) if args.regions is None else _region_runner(
            service, replace(settings, fleet=specs[0].robots), layouts[specs[0].name], live))
    # one recovery for the whole portal (every in-process arena's jobs); remote runners' jobs follow their leases
    from swarmdeck.console.portal.exports import JobExports
    from swarmdeck.console.portal.remote import LeaseReaper, RemoteArenas
    from swarmdeck.console.portal.runner import recover_recordings

    exports = runners[0].exports if runners else JobExports(service)
    try:
        interrupted = service.recover_on_start()
        exports.resume()
        recover_recordings(service, exports, interrupted)
    except sqlite3.DatabaseError as exc:
        sock.close()
        service.close()
        os.umask(caller_umask)
        raise UsageError(f"the database in {args.data!r} is damaged: {exc}") from None
    for job_id in interrupted:
        print(f"swarmdeck server: job {job_id} was on the arena when the server stopped: interrupted "
              "(partial recording kept)", file=sys.stderr)
    if args.arena_specs:
        service.runners = {r.settings.name or "": r for r in runners}
    else:
        service.arena = runners[0]
    from swarmdeck.console.portal.notify import Notifier

    notifier = Notifier(service.lab, smtp).start()
    service.remote = remote = RemoteArenas(service, exports)
    reaper = LeaseReaper(remote).start()  # remote runners that went silent: their jobs interrupted
    view = None
    if args.console_port is not None:
        from swarmdeck.console.portal.operator_view import OperatorView

        try:
            view = OperatorView(args.host, args.console_port)
        except OSError as exc:
            sock.close()
            service.close()
            raise UsageError(f"--console-port {args.console_port}: {exc.strerror or exc}") from None
        for r in runners:
            r.frame_listeners.append(view.offer)
        print(f"swarmdeck server: operator view at {view.url}", flush=True)
    projector = None
    if args.projector is not None:
        from swarmdeck.console.projector.server import ProjectorServer

        try:
            projector = ProjectorServer(runners[0].settings.bounds, _projector_calibration(args), host=args.host,
                                        port=args.projector)
        except OSError as exc:
            if view is not None:
                view.close()
            sock.close()
            service.close()
            raise UsageError(f"--projector: cannot serve on {args.host}:{args.projector}: "
                             f"{exc.strerror or exc}") from None

        runners[0].frame_listeners.append(projector.offer)
        if view is not None:  # the operator page's Projector folder: layers, brightness, blackout
            view.add_projector(projector)
        projector.start()
        print(f"swarmdeck server: projector page at {projector.url}" + (
            "" if projector.feed.calibration is not None else " (no homography: run `swarmdeck calibrate projector`)"),
            flush=True)
    workers = VerificationWorkers(service, executor, obstacles=obstacles,
                                  concurrent=args.verify_concurrent).start()
    for r in runners:
        r.start()
    sweeper = RetentionSweeper(service).start() if args.retain_days is not None else None
    app = create_app(service, live=live, http=http)
    server = uvicorn_server(app, log_level=args.log_level, http=http)
    host = f"[{args.host}]" if ":" in args.host else args.host
    arena = args.robots_via and f"MQTT robots 0..{fleet - 1} via {_redacted(args.robots_via)}" or \
        f"{fleet} simulated robots docked on the chargers{' (fast)' if args.fast else ''}"
    if args.arena_specs:
        arena = "arenas " + "; ".join(s.describe() for s in specs)
    print(f"swarmdeck server: http://{host}:{sock.getsockname()[1]}  ({arena}; data in {args.data}; "
          "API docs at /docs; Ctrl-C to stop)", flush=True)
    print(f"swarmdeck server: user code confined by: {describe(JailConfig(allow_no_cgroup=args.allow_no_cgroup))}",
          flush=True)
    import signal

    # uvicorn stops on SIGINT/SIGTERM and then re-raises the signal to the handler it found: make that a
    # no-op, so the shutdown below (runner: robots stopped; workers; database) always runs and we exit 0.
    saved = {sig: signal.signal(sig, lambda signum, frame: None) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        server.run(sockets=[sock])
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, handler)
        for r in runners:
            r.stop()
        if not runners:
            exports.stop()
        reaper.stop()
        notifier.stop()
        workers.stop()
        if sweeper is not None:
            sweeper.stop()
        if view is not None:
            view.close()
        if projector is not None:
            projector.close()
        sock.close()
        service.close()
        print("swarmdeck server: stopped (robots stopped)", file=sys.stderr)
    return 0


def _projector_calibration(args: argparse.Namespace):
    """The arena's projector calibration (None: no --projector, or no calibration yet); UsageError naming a bad
    port, a --projector-calibration without --projector, or an unusable calibration."""
    if args.projector is None:
        if args.projector_calibration is not None:
            raise UsageError("--projector-calibration needs --projector")
        return None
    if not 0 <= args.projector <= 65535:
        raise UsageError(f"--projector port must be in [0, 65535], got {args.projector}")
    from swarmdeck.console.projector.server import projector_calibration
    from swarmdeck.core.bounds import DEFAULT_BOUNDS
    from swarmdeck.tracking.projector import ProjectorCalibrationError

    try:
        return projector_calibration(args.projector_calibration, DEFAULT_BOUNDS)  # the portal's arena floor
    except ProjectorCalibrationError as exc:
        raise UsageError(f"--projector-calibration: {exc}") from None


def _redacted(url: str) -> str:
    from swarmdeck.devices.net.mqtt_config import redact_url

    return redact_url(url)

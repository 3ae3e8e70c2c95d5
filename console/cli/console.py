"""``swarmdeck console``: the operator console in the browser (simulated robots unless told otherwise)."""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from typing import Any

from swarmdeck.console.cli import UsageError

NAME = "console"
HELP = "start the operator console (control loop + browser view) and print its URL"
ORDER = 1


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", default=None, help="interface to bind (default 127.0.0.1: this machine only)")
    parser.add_argument("--port", type=int, default=None, help="TCP port (default 8080; 0 picks a free one)")
    parser.add_argument("--robots", type=int, default=None, metavar="N",
                        help="number of simulated robots (default 12; as many as fit the arena, e.g. 1000 "
                             "with --arena 10x6: the barrier goes distributed above 200)")
    parser.add_argument("--arena", default=None, metavar="WxH",
                        help="arena size in metres, centred on the origin (default 3.2x2)")
    parser.add_argument("--behaviour", "--behavior", default=None,
                        help="coverage (default) | rendezvous | formation | goto | decentralised (rendezvous by "
                             "messages only, over a lossy network: docs/network.md) | script:PATH "
                             "(PATH defines behaviour(poses, t) -> (N, 2) velocities in m/s)")
    parser.add_argument("--config", default=None, metavar="FILE", help="TOML file ([console], [behaviour], "
                        "[safety], [density], [inputs] tables)")
    parser.add_argument("--seed", type=int, default=None, help="seed for the random initial poses")
    parser.add_argument("--duration", type=float, default=None, metavar="S",
                        help="stop after S seconds (scripted/headless use); default: run until Ctrl-C")
    parser.add_argument("--camera", default=None, metavar="SPEC",
                        help="track the robots with an overhead camera: 'synthetic' (rendered from the "
                             "simulation), a webcam INDEX, a stream URL, a video FILE or a folder of images")
    parser.add_argument("--robots-via", default=None, metavar="URL",
                        help="drive GRITSBots over MQTT instead of simulating them, e.g. mqtt://127.0.0.1:1883 "
                             "(try `swarmdeck robots --broker URL` for a simulated fleet)")
    parser.add_argument("--start", choices=("random", "docked"), default="random",
                        help="where the simulated robots start: random on the floor (default) or docked on the "
                             "charging strips along the walls (robot k on slot k), with batteries that charge "
                             "while docked and drain while driving (the panel's Fleet buttons set them up and "
                             "return them)")
    parser.add_argument("--virtual", type=int, default=None, metavar="K",
                        help="add K virtual robots, simulated in the console beside the physical ones (--robots-via, "
                             "or the simulation standing in for them): the barrier makes every robot avoid every "
                             "other; the scene draws virtual robots pale and ringed; recordings mark them")
    parser.add_argument("--record", default=None, metavar="PATH",
                        help="record the session to PATH (MCAP; default sessions/<UTC time>.mcap)")
    parser.add_argument("--no-record", action="store_true", help="do not record the session")
    parser.add_argument("--foxglove-channels", action=argparse.BooleanOptionalAction, default=None,
                        help="write Foxglove's own channels (3D scene, poses, grid, log, metrics) into the "
                             "recording beside swarmdeck's (default on; --no-foxglove-channels: a file ≈ 6x "
                             "smaller at 100 robots that Foxglove still opens as raw messages; [console] "
                             "foxglove_channels in --config's [recording])")
    parser.add_argument("--foxglove-entities", action="store_true",
                        help="record the robots for Foxglove as before packing was the default: a disc, an arrow and "
                             "a label per robot on /foxglove/robots and /foxglove/poses, every frame up to 100 robots "
                             "(≈ 4x larger at 100 robots; default: one packed PointCloud, /foxglove/robot_points, "
                             "10 scenes/s at 100 robots; [recording] packed = false)")
    parser.add_argument("--foxglove", nargs="?", type=int, const=8765, default=None, metavar="PORT",
                        help="also serve the run live to Foxglove over its WebSocket protocol (default port 8765, "
                             "on --host; clients asking for foxglove.sdk.v1 or foxglove.websocket.v1 are both "
                             "served): open ws://127.0.0.1:PORT in Foxglove and import `swarmdeck foxglove-layout`")
    parser.add_argument("--sensors", action="store_true", default=None,
                        help="give the robots Robotarium 2.0's sensors (seven ToF distance sensors, encoders, IMU, "
                             "LEDs; docs/sensing.md): every Frame carries their readings, the scene draws the rays "
                             "(layer 'sensors'), recordings keep them ([console] sensors = true in --config)")
    parser.add_argument("--coverage-worker", choices=("auto", "on", "off"), default=None,
                        help="run the coverage behaviour two ticks behind on two worker threads (one builds the "
                             "Voronoi diagram, one integrates the cells), overlapping the barrier and the Frame: "
                             "'auto' (default) from 2000 robots; the barrier still certifies every command at the "
                             "current poses (docs/console-scale.md; [console] coverage_worker in --config)")
    parser.add_argument("--projector", nargs="?", type=int, const=8090, default=None, metavar="PORT",
                        help="also serve the overhead projector's page on http://HOST:PORT/projector (default port "
                             "8090): open it full screen on the projector (`chromium --kiosk --app=URL`); it "
                             "draws the density, cells, goals, halos… warped onto the floor (layers, brightness "
                             "and blackout in the panel's Projector folder)")
    parser.add_argument("--projector-calibration", default=None, metavar="FILE",
                        help="the projector's homography from `swarmdeck calibrate projector` (default "
                             "projector.json if it exists; without one the page says to calibrate)")
    parser.add_argument("--no-inputs", action="store_true",
                        help="do not open the TUIO/OSC input listeners (UDP 3333 by default)")


#: what an interrupt during start-up closes, in this order: the servers, the loop (robots stopped) or, before it
#: exists, the inputs and the robots' sink, then the recording (its summary and index written).
_CLOSE_ORDER = ("projector", "bridge", "app", "loop", "hub", "sink", "rec")


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.runtime.behaviours import BehaviourError, make_behaviour
    from swarmdeck.console.runtime.config import ConfigFileError, ConsoleSettings, load_settings
    from swarmdeck.console.runtime.loop import LoopConfig

    try:
        settings = load_settings(args.config) if args.config else ConsoleSettings(LoopConfig())
    except ConfigFileError as exc:
        raise UsageError(str(exc)) from None
    changes = {}
    if args.robots is not None:
        if args.robots < 1:
            raise UsageError(f"--robots must be >= 1, got {args.robots}")  # the option's name, not the config key's
        changes["n_robots"] = args.robots
    if args.behaviour is not None:
        changes["behaviour"] = args.behaviour
    if args.seed is not None:
        changes["seed"] = args.seed
    if args.sensors:
        changes["sensors"] = True
    if args.coverage_worker is not None:
        changes["coverage_worker"] = args.coverage_worker
    if args.arena is not None:
        from swarmdeck.console.runtime.config import arena_bounds

        try:
            changes["bounds"] = arena_bounds(args.arena)
        except ValueError as exc:
            raise UsageError(f"--arena: {exc}") from None
    try:
        config = replace(settings.loop, **changes)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    host = args.host if args.host is not None else settings.host
    port = args.port if args.port is not None else settings.port
    if not 0 <= port <= 65535:
        raise UsageError(f"--port must be in [0, 65535], got {port}")
    if args.foxglove is not None and not 0 <= args.foxglove <= 65535:
        raise UsageError(f"--foxglove port must be in [0, 65535], got {args.foxglove}")
    if args.duration is not None and not args.duration > 0:
        raise UsageError(f"--duration must be > 0 s, got {args.duration}")
    if args.start == "docked" and (args.robots_via or args.camera):
        raise UsageError("--start docked places simulated robots; physical robots start where they are "
                         "(`swarmdeck robots --start docked` for the simulated MQTT fleet)")
    if args.virtual is not None and args.virtual < 1:
        raise UsageError(f"--virtual must be a number of robots >= 1, got {args.virtual}")

    projector_cal = _projector(args, config.bounds)
    if args.record and args.no_record:
        raise UsageError("--record and --no-record exclude each other")
    _check_address(host, port)
    from swarmdeck.core.robot_models import robot_params

    robot = robot_params(settings.robot_model)  # [arena] robot_model (the GRITSBot by default)
    try:  # check the behaviour (name, script) before opening anything
        make_behaviour(config.behaviour, config.behaviour_params, config.bounds, config.max_speed,
                       config.safety.safety_distance)
    except BehaviourError as exc:
        raise UsageError(str(exc)) from None
    try:
        source, sink = _robots(config, args.camera, args.robots_via, args.virtual, docked=args.start == "docked",
                               robot=robot)
    except (ValueError, OSError) as exc:
        raise UsageError(str(exc)) from None
    started: dict[str, Any] = {"sink": sink.close}  # closers of what start-up has opened, by name
    restore = _stop_on_signals()  # SIGTERM/SIGHUP act as Ctrl-C from here on, start-up included
    try:
        return _serve(args, settings, config, source, sink, robot, host, port, projector_cal, started)
    except KeyboardInterrupt:
        if not started:  # the run's own try/finally had taken over and closed everything
            raise
        # interrupted while starting: stop the robots, then close the recording, before leaving
        for name in _CLOSE_ORDER:
            try:
                if name in started:
                    started[name]()
            except Exception as exc:  # noqa: BLE001 - keep closing the rest
                print(f"swarmdeck console: while stopping: {exc}", file=sys.stderr)
        print("swarmdeck console: interrupted while starting (robots stopped)", file=sys.stderr)
        return 130
    finally:
        restore()


def _serve(args: argparse.Namespace, settings: Any, config: Any, source: Any, sink: Any, robot: Any, host: str,
           port: int, projector_cal: Any, started: dict[str, Any]) -> int:
    """Open the recorder, inputs, loop, servers; run until the duration, Ctrl-C, SIGTERM or SIGHUP. Each
    thing opened puts its closer in ``started`` (emptied once the run's own try/finally owns them), so an
    interrupt during start-up closes what is open, in :data:`_CLOSE_ORDER`: :func:`main`."""
    from swarmdeck.console.runtime.behaviours import BehaviourError
    from swarmdeck.console.runtime.loop import ControlLoop
    from swarmdeck.core.ports import ProvidesImage
    rec = None
    if not args.no_record:
        from swarmdeck.devices.net.mqtt_config import redact_url  # never record a broker password

        source_name = args.camera or (redact_url(args.robots_via) if args.robots_via else "simulation")
        fox = settings.foxglove_channels if args.foxglove_channels is None else args.foxglove_channels
        images = source.image if isinstance(source, ProvidesImage) else None
        rec = _recorder(args.record, config, settings.inputs, source_name, images,
                        virtual=args.virtual or 0, foxglove_channels=fox, chunk_frames=settings.chunk_frames,
                        **_foxglove_form(settings, args.foxglove_entities))
        started["rec"] = lambda: print(f"swarmdeck console: {rec.close().message}", file=sys.stderr)
    hub = None
    if not args.no_inputs:
        hub = _start_inputs(settings.inputs, rec)
        if hub is not None:
            started["hub"] = hub.close
    try:
        # One monotonic clock for the loop and the input listeners' receive stamps.
        loop = ControlLoop(config, source=source, sink=sink, inputs=hub, contact_density=_contact_density(hub),
                           clock=time.monotonic, robot=robot)
    except (BehaviourError, ValueError) as exc:
        sink.close()
        if hub is not None:
            hub.close()
        if rec is not None:
            rec.close()
        raise UsageError(str(exc)) from None
    started.pop("sink")  # the loop owns the robots' sink and the inputs now: closing it stops the robots
    started.pop("hub", None)
    started["loop"] = loop.close
    if rec is not None:
        rec.follow(loop)  # its Frames and typed operator actions (re-simulation replays them)
        loop.add_health("recording", lambda: rec.status().message)
        print(f"swarmdeck console: recording to {rec.path}", file=sys.stderr)

    from swarmdeck.console.web.app import ConsoleApp

    bridge = None
    if args.foxglove is not None:
        from swarmdeck.console.web.foxglove_live import FoxgloveBridge, FoxglovePortInUse

        try:
            bridge = FoxgloveBridge(config.bounds, host=host, port=args.foxglove, robot_radius=loop.robot.radius,
                                    image_provider=source.image if isinstance(source, ProvidesImage) else None)
        except FoxglovePortInUse as exc:
            loop.close()
            if rec is not None:
                rec.close()
            raise UsageError(f"{exc}: choose another with --foxglove PORT") from None
        started["bridge"] = bridge.close
    try:
        app = ConsoleApp(loop, host=host, port=port)
    except OSError as exc:
        loop.close()
        if bridge is not None:
            bridge.close()
        raise UsageError(f"cannot serve on {host}:{port}: {exc}") from None
    started.pop("loop")  # the app owns the loop now (its close stops the loop, the viewer and the server)
    started["app"] = app.close
    projector = None
    if args.projector is not None:
        from swarmdeck.console.projector.server import ProjectorServer
        from swarmdeck.console.web.projector_panel import ProjectorPanel

        try:
            projector = ProjectorServer(config.bounds, projector_cal, host=host, port=args.projector)
        except OSError as exc:
            app.close()
            if bridge is not None:
                bridge.close()
            if rec is not None:
                rec.close()
            raise UsageError(f"--projector: cannot serve on {host}:{args.projector}: {exc}") from None
        started["projector"] = projector.close
        loop.subscribe(projector.offer)
        ProjectorPanel(app.gui.gui, projector, on_error=loop.post)
        projector.start()
        print(f"swarmdeck console: projector page at {projector.url}" +
              ("" if projector_cal is not None else " (no homography: run `swarmdeck calibrate projector`)"),
              flush=True)
    if bridge is not None:
        loop.subscribe(bridge.offer)
        bridge.start()
        print(f"swarmdeck console: Foxglove live at {bridge.url} (import `swarmdeck foxglove-layout`)", flush=True)
    app.start()
    if port and app.port != port:
        print(f"swarmdeck console: port {port} is in use; serving on port {app.port} instead", file=sys.stderr)
    started.clear()  # from here the try/finally below closes everything
    try:
        virtual = f" + {args.virtual} virtual" if args.virtual else ""
        print(f"swarmdeck console: {app.url}  ({config.n_robots}{virtual} robots, {loop.behaviour_name}; "
              "Ctrl-C to stop)", flush=True)
        app.wait(args.duration)
    except KeyboardInterrupt:
        print("swarmdeck console: stopping (robots stopped)", file=sys.stderr)
    finally:
        frame = loop.latest
        app.close()
        if projector is not None:
            projector.close()
        if bridge is not None:
            bridge.close()
        if rec is not None:
            st = rec.close()
            print(f"swarmdeck console: {st.message}", file=sys.stderr)
    if frame is not None and args.duration is not None:
        b = frame.barrier
        print(f"ran {frame.tick + 1} ticks, t = {frame.run_time:.1f} s; "
              f"min distance {b.min_distance:.3f} m" if b is not None else "")
    return 0


def _projector(args: argparse.Namespace, bounds):
    """The projector's calibration for ``--projector`` (None: none yet), or UsageError naming the problem."""
    if args.projector is None:
        if args.projector_calibration is not None:
            raise UsageError("--projector-calibration needs --projector")
        return None
    if not 0 <= args.projector <= 65535:
        raise UsageError(f"--projector port must be in [0, 65535], got {args.projector}")
    from swarmdeck.console.projector.server import projector_calibration
    from swarmdeck.tracking.projector import ProjectorCalibrationError

    try:
        return projector_calibration(args.projector_calibration, bounds)
    except ProjectorCalibrationError as exc:
        raise UsageError(f"--projector-calibration: {exc}") from None


def _stop_on_signals():
    """SIGTERM (systemd, docker, most supervisors) and SIGHUP (the terminal closed) stop the console as
    Ctrl-C does: robots stopped, recording closed with its summary. Returns a function restoring
    the previous handlers."""
    import signal

    def interrupt(signum, frame):  # noqa: ARG001 - signal handler signature
        raise KeyboardInterrupt(signal.Signals(signum).name)

    saved = {sig: signal.signal(sig, interrupt) for sig in (signal.SIGTERM, signal.SIGHUP)}

    def restore() -> None:
        for sig, handler in saved.items():
            signal.signal(sig, handler)

    return restore


def _check_address(host: str, port: int) -> None:
    """UsageError (one line) unless ``host`` is an address of this machine the console can bind.

    A host this machine does not have made the web server retry for a long time before; a busy
    port is fine here (the server moves to the next free port and the console says so). Only a
    local bind is attempted: nothing is sent anywhere.
    """
    import errno
    import socket

    try:
        family, kind, proto, _, address = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM,
                                                             flags=socket.AI_PASSIVE)[0]
    except (socket.gaierror, UnicodeError) as exc:
        raise UsageError(f"--host {host}: not a known name or address ({exc})") from None
    with socket.socket(family, kind, proto) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(address)
        except OSError as exc:
            if exc.errno == errno.EADDRINUSE:
                return
            if exc.errno == errno.EADDRNOTAVAIL:
                raise UsageError(f"--host {host}: not an address of this machine (use 127.0.0.1, 0.0.0.0 "
                                 f"or one of this machine's addresses)") from None
            raise UsageError(f"cannot serve on {host}:{port}: {exc.strerror or exc}") from None


def _robots(config, camera: str | None, robots_via: str | None, virtual: int | None = None, docked: bool = False,
            robot=None):
    """(pose source, command sink) from the one robots factory (:func:`~swarmdeck.console.runtime.hardware.open_robots`):
    simulation by default, MQTT robots with --robots-via, camera poses with --camera, plus ``virtual`` virtual
    robots simulated here. Raises ValueError/OSError naming what could not be opened."""
    from swarmdeck.console.runtime.hardware import RobotsSpec, open_robots

    extra = {} if robot is None else {"params": robot}  # the robot model of [arena] robot_model
    ports = open_robots(RobotsSpec(n_robots=config.n_robots, bounds=config.bounds, dt=config.dt, seed=config.seed,
                                   robots_via=robots_via, docked=docked, camera=camera, virtual=virtual or 0,
                                   obstacles=config.obstacles, **extra))
    return ports.source, ports.sink


def _foxglove_form(settings, entities: bool) -> dict[str, Any]:
    """``robot_rate``, ``packed``, ``lines_period`` of the recording's Foxglove channels: the config file's
    ``[recording]`` (default packed), or with ``--foxglove-entities`` the per-robot form
    (:meth:`~swarmdeck.console.recording.foxglove.FoxgloveConfig.per_entity`)."""
    if entities:
        from swarmdeck.console.recording.foxglove import FoxgloveConfig

        form = FoxgloveConfig.per_entity()
        return {"robot_rate": form.robot_rate, "packed": form.packed, "lines_period": form.lines_period}
    return {"robot_rate": settings.robot_rate, "packed": settings.packed, "lines_period": settings.lines_period}


def _recorder(path: str | None, config, inputs_table: dict | None, source: str, image_provider=None,
              virtual: int = 0, foxglove_channels: bool = True, chunk_frames: int = 20, robot_rate: float = 1000.0,
              packed: bool = True, lines_period: float = 1.0):
    """The session recorder (MCAP), writing in the background; never raises into the run. ``image_provider``
    (the camera source's ``image``) feeds the Foxglove camera channel; ``virtual``: how many virtual robots
    (each Frame's ``is_virtual`` says which); ``foxglove_channels``: also write Foxglove's own channels;
    ``chunk_frames``: frames per chunk; ``robot_rate``, ``packed``, ``lines_period``: the Foxglove channels'
    (``FoxgloveConfig``; the config file's [recording])."""
    from swarmdeck.console.recording.capsule import session_capsule
    from swarmdeck.console.recording.foxglove import FoxgloveConfig
    from swarmdeck.console.recording.recorder import Recorder, RecorderConfig, default_path
    from swarmdeck.console.recording.resimulate import session_metadata

    extra: dict[str, Any] = {"virtual_robots": int(virtual)} if virtual else {}
    metadata = session_metadata(config, inputs_table, source=source, **extra)
    return Recorder(path or default_path(), metadata,
                    RecorderConfig(foxglove=foxglove_channels, chunk_frames=chunk_frames),
                    image_provider=image_provider, foxglove=FoxgloveConfig(robot_rate=robot_rate, packed=packed,
                                                                            lines_period=lines_period),
                    capsule=session_capsule(metadata))


def _start_inputs(table: dict | None, rec=None):
    """The TUIO/OSC listeners of ``[inputs]`` (default: TUIO on UDP 3333), started; None if they cannot bind.
    Raw datagrams go to the recorder, if any."""
    from swarmdeck.inputs import ConfigError, InputConfig, InputHub

    try:
        cfg = InputConfig.from_dict(table) if table is not None else InputConfig()
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    hub = InputHub.from_config(cfg, clock=time.monotonic, on_datagram=rec.raw_datagram if rec is not None else None)
    try:
        hub.start()
    except OSError as exc:
        print(f"swarmdeck console: inputs disabled: {exc}", file=sys.stderr)
        return None
    names = ", ".join(f"{s.config.name} ({type(s).__name__.replace('Listener', '').upper()} "
                      f"{getattr(s, 'address', ('', s.config.port))[1]})" for s in hub.sources)
    print(f"swarmdeck console: listening for inputs: {names}", file=sys.stderr)
    return hub


def _contact_density(hub):
    if hub is None:
        return None
    from swarmdeck.inputs import ContactDensity

    return ContactDensity(hub.config.density)

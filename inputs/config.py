"""Input configuration: listeners (ports, transports, presets, calibration) and
the contacts-to-density settings, loadable from a dict or a TOML ``[inputs]`` table.

Example (``swarmdeck.toml``)::

    [inputs]
    bounds = [-1.6, 1.6, -1.0, 1.0]      # arena, m (default)

    [[inputs.listeners]]                  # a TUIO tablet on UDP 3333
    port = 3333
    host = "0.0.0.0"                      # accept a phone/tablet on the LAN
    timeout = 1.0                         # s of silence before its contacts are lost
    max_contacts_per_source = 64          # limits (defaults shown) a tablet never reaches
    max_contacts = 256
    calibration = { flip_y = false, rotation_deg = 0, scale = [1, 1], offset = [0, 0] }

    [[inputs.listeners]]                  # a Leap through ManosOsc (port 7110)
    preset = "manososc"

    [[inputs.listeners]]                  # TUIO/TCP (4-byte length framing)
    transport = "tcp"
    port = 3334

    [inputs.density]
    sigma = 0.3
    fade = 0.4

Without an ``[inputs]`` table there is one UDP TUIO listener on 127.0.0.1:3333.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds
from swarmdeck.core.checks import in_range
from swarmdeck.core.config import ConfigError, check_keys, field_names, read_toml

from .calibration import Calibration
from .density import DensityConfig
from .pointstream import PRESETS, PointStreamConfig


@dataclass(frozen=True)
class ListenerConfig:
    """One input socket.

    Attributes:
        name: label shown in the monitor.
        transport: ``"udp"`` (TUIO/UDP, OSC) or ``"tcp"`` (TUIO/TCP: each OSC
            packet preceded by its 4-byte big-endian length).
        host, port: where to bind (port 0 = any free port). Default 127.0.0.1:3333;
            use ``0.0.0.0`` for a tablet or phone on the network.
        tuio: decode ``/tuio/*`` (1.1) and ``/tuio2/*`` (2.0) messages.
        streams: generic OSC point streams decoded on this socket.
        calibration: default surface → arena map of this listener's sources.
        source_calibrations: ``(glob on the source name, Calibration)`` pairs tried
            first, e.g. ``("*TuioPad@*", Calibration(flip_x=True))``.
        timeout: s of silence after which a source's contacts are lost.
        max_datagram: bytes; larger datagrams are rejected and counted.
        future_tolerance: s a bundle timetag may lead the wall clock before it is
            counted as a ``future_timetag`` quirk (it is never waited for).
        max_osc_arguments: decode budget of one datagram: each OSC message counts one
            plus its arguments; a datagram over it is rejected (``too_many_arguments``)
            before it is decoded. 2048 holds a 64-finger blob frame twice over.
        max_contacts_per_source: contacts one source may hold; further fingers of a
            frame are dropped and counted (``too_many_contacts``), contacts it already
            has are kept first.
        max_contacts: contacts of all sources of this listener together (same counting).
        max_events: contact events kept between two polls; older ones are dropped and
            counted (``events_dropped`` in the listener's totals).
        forget_after: s of silence after which a source without contacts is forgotten
            (its health entry and decoder state; its counts stay in the listener's
            lifetime totals). At least ``timeout`` is used.
        max_reported_sources: sources a poll reports (those with contacts first, then
            the most recently heard), besides the listener's totals entry and one
            ``N more sources`` entry — the bound on what every console Frame carries.
    """

    name: str = "tuio"
    transport: str = "udp"
    host: str = "127.0.0.1"
    port: int = 3333
    tuio: bool = True
    streams: tuple[PointStreamConfig, ...] = ()
    calibration: Calibration = field(default_factory=Calibration)
    source_calibrations: tuple[tuple[str, Calibration], ...] = ()
    timeout: float = 1.0
    max_datagram: int = 65536
    future_tolerance: float = 0.5
    max_osc_arguments: int = 2048
    max_contacts_per_source: int = 64
    max_contacts: int = 256
    max_events: int = 1024
    forget_after: float = 30.0
    max_reported_sources: int = 16

    def __post_init__(self) -> None:
        if self.transport not in ("udp", "tcp"):
            raise ConfigError(f"listener {self.name!r}: transport must be 'udp' or 'tcp', got {self.transport!r}")
        if not in_range(self.port, 0, 65535, integer=True):
            raise ConfigError(f"listener {self.name!r}: port must be an int in 0..65535, got {self.port!r}")
        if not in_range(self.timeout, 0.0, lo_open=True):
            raise ConfigError(f"listener {self.name!r}: timeout must be a positive number of seconds, got {self.timeout!r}")
        if not in_range(self.max_datagram, 16, 65536, integer=True):
            raise ConfigError(f"listener {self.name!r}: max_datagram must be an int in 16..65536, got {self.max_datagram!r}")
        for key, lo, hi in (("max_osc_arguments", 16, 1 << 20), ("max_contacts_per_source", 1, 1 << 16),
                            ("max_contacts", 1, 1 << 20), ("max_events", 1, 1 << 20),
                            ("max_reported_sources", 1, 4096)):
            v = getattr(self, key)
            if not (type(v) is int and lo <= v <= hi):
                raise ConfigError(f"listener {self.name!r}: {key} must be an int in {lo}..{hi}, got {v!r}")
        if not in_range(self.forget_after, 0.0, lo_open=True):
            raise ConfigError(f"listener {self.name!r}: forget_after must be a positive number of seconds, "
                              f"got {self.forget_after!r}")

    @classmethod
    def from_preset(cls, preset: str, **overrides) -> ListenerConfig:
        """A UDP listener for a gesture-bridge preset (``manososc``, ``leap-osc``,
        ``ultraleap-osc-sender``) or ``tuio``; ``overrides`` replace fields."""
        if preset == "tuio":
            return cls(**overrides)
        if preset not in PRESETS:
            raise ConfigError(f"unknown preset {preset!r}; known: tuio, {', '.join(sorted(PRESETS))}")
        streams = PRESETS[preset]
        kw = {"name": preset, "tuio": False, "streams": streams,
              "port": streams[0].port if streams[0].port is not None else 3333}
        kw.update(overrides)
        return cls(**kw)

    @classmethod
    def from_dict(cls, d: dict, bounds: tuple[float, float, float, float] | None = None) -> ListenerConfig:
        """Build from a mapping (a ``[[inputs.listeners]]`` TOML table)."""
        kw = check_keys(d, field_names(cls) | {"preset"}, "listener")
        preset = kw.pop("preset", None)
        try:
            if "calibration" in kw:
                kw["calibration"] = Calibration.from_dict(kw["calibration"], bounds)
            elif bounds is not None:
                kw["calibration"] = Calibration(bounds=tuple(bounds))  # type: ignore[arg-type]  # 4 numbers: Calibration checks
            if "source_calibrations" in kw:
                sc = kw["source_calibrations"]
                if not isinstance(sc, dict):
                    raise ConfigError("source_calibrations must be a table {glob = {calibration...}}")
                kw["source_calibrations"] = tuple((k, Calibration.from_dict(v, bounds)) for k, v in sc.items())
            if "streams" in kw:
                kw["streams"] = tuple(PointStreamConfig.from_dict(s) for s in kw["streams"])
            if preset is not None:
                return cls.from_preset(preset, **kw)
            return cls(**kw)
        except ConfigError:
            raise
        except (ValueError, TypeError) as exc:
            raise ConfigError(f"listener {d.get('name', preset or '')!r}: {exc}") from None


@dataclass(frozen=True)
class InputConfig:
    """All inputs of a console: listeners plus the density built from contacts."""

    listeners: tuple[ListenerConfig, ...] = (ListenerConfig(),)
    density: DensityConfig = field(default_factory=DensityConfig)
    bounds: Bounds = DEFAULT_BOUNDS

    @classmethod
    def from_dict(cls, d: dict) -> InputConfig:
        """Build from the ``[inputs]`` mapping; unknown keys are an error."""
        check_keys(d, ("listeners", "density", "bounds"), "[inputs]")
        bounds = check_bounds(d.get("bounds", DEFAULT_BOUNDS), "[inputs] bounds", ConfigError)
        raw = d.get("listeners", [{}])
        if not isinstance(raw, list):
            raise ConfigError("[inputs] listeners must be an array of tables ([[inputs.listeners]])")
        listeners = tuple(ListenerConfig.from_dict(x, bounds) for x in raw)
        try:
            density = DensityConfig.from_dict(d.get("density", {}))
        except (ValueError, TypeError) as exc:
            raise ConfigError(f"[inputs.density]: {exc}") from None
        return cls(listeners, density, bounds)

    @classmethod
    def load_toml(cls, path: str | Path, section: str = "inputs") -> InputConfig:
        """Read ``[section]`` of a TOML file (defaults if the table is absent)."""
        return cls.from_dict(read_toml(path).get(section, {}))

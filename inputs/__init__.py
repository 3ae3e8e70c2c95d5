"""swarmdeck.inputs: human inputs (TUIO 1.1/2.0 over UDP or TCP, generic OSC
point streams from gesture bridges) → calibrated :class:`Contact` s in arena
metres → :class:`ContactDensity`, a time-varying density for coverage control.

See ``hub.py`` for how the console constructs and polls the listeners.
"""
from .calibration import Calibration
from .capture import Capture, Datagram, read_jsonl, replay, write_jsonl
from .config import ConfigError, InputConfig, ListenerConfig
from .contact import Contact, ContactEvent, InputSnapshot, InputWork, SourceHealth
from .density import ContactDensity, DensityConfig
from .hub import InputHub
from .listener import InputSource, TcpListener, UdpListener, make_listener
from .oscparse import MalformedDatagram, parse_datagram
from .pointstream import PRESETS, PointStreamConfig

__all__ = [
    "Calibration", "Capture", "ConfigError", "Contact", "ContactDensity", "ContactEvent", "Datagram",
    "DensityConfig", "InputConfig", "InputHub", "InputSnapshot", "InputSource", "InputWork", "ListenerConfig",
    "MalformedDatagram", "PRESETS", "PointStreamConfig", "SourceHealth", "TcpListener", "UdpListener",
    "make_listener", "parse_datagram", "read_jsonl", "replay", "write_jsonl",
]

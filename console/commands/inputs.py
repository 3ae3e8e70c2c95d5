"""``swarmdeck inputs monitor|send``: watch TUIO/OSC sources, or send demo touches (see swarmdeck.inputs.cli)."""
from swarmdeck.inputs.cli import HELP, NAME, add_arguments, main  # noqa: F401

ORDER = 40

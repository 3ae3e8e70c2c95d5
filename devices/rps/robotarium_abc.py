"""rps's ``robotarium_abc`` names (the constants of the Robotarium), for scripts that read them."""
from swarmdeck.devices.robotarium_constants import *  # noqa: F401,F403

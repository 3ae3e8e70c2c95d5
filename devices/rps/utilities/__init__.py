"""rps.utilities counterparts (see :mod:`swarmdeck.devices.rps`)."""

"""gym 0.26's names MARBLER imports (``gym.spaces``, ``gym.envs.registration.register``), over gymnasium (tests only)."""
from . import envs, spaces  # noqa: F401

"""swarmdeck.coverage: time-varying-density coverage control (REFERENCE.md §5)."""
from swarmdeck.coverage.density import Density, GaussianMixture

__all__ = ["Density", "GaussianMixture"]

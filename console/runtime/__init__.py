"""console/runtime."""

"""console/web."""

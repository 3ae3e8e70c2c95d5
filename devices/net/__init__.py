"""devices/net."""

from gymnasium.spaces import Box, Discrete, Tuple  # noqa: F401

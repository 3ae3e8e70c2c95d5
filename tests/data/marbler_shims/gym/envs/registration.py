def register(env_id, **kwargs):
    """MARBLER registers its scenarios with gym for EPyMARL's training: not needed to run them."""

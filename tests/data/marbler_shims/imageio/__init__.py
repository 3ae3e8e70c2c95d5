"""MARBLER saves GIFs of its episodes with ``imageio.mimsave``: a no-op here (tests only; the frames are
still drawn from the facade's headless figure)."""


def mimsave(path, frames, **kwargs):
    pass

"""A tiny numpy stand-in for the part of torch MARBLER's evaluation uses (tests only, not swarmdeck):
``torch.Tensor(x)``, ``.detach().numpy()``, ``torch.load`` (here: an ``.npz`` of the state dict) and
``torch.device``. Enough to run MARBLER's pretrained-policy loop without a 700 MB CPU torch."""
import numpy as np

from . import nn  # noqa: F401


class _Tensor(np.ndarray):
    def detach(self):
        return self

    def numpy(self):
        return np.asarray(self)


def Tensor(data):  # noqa: N802 - torch's name
    return np.asarray(data, dtype=np.float32).view(_Tensor)


def device(name):
    return name


def load(path, map_location=None):
    with np.load(path) as data:
        return {k: Tensor(data[k]) for k in data.files}

"""``torch.nn``'s Module, Linear and GRUCell in numpy (float32), for MARBLER's RNNAgent (tests only)."""
import numpy as np

from . import functional  # noqa: F401


class Module:
    def __call__(self, *args):
        from torch import Tensor

        out = self.forward(*args)
        return tuple(Tensor(o) for o in out) if isinstance(out, tuple) else Tensor(out)

    def load_state_dict(self, state):
        for key, value in state.items():
            owner, name = key.rsplit(".", 1)
            target = self
            for part in owner.split("."):
                target = getattr(target, part)
            current = getattr(target, name)
            if current.shape != value.shape:
                raise RuntimeError(f"size mismatch for {key}: {value.shape} vs {current.shape}")
            setattr(target, name, np.asarray(value, dtype=np.float32))


class Linear(Module):
    def __init__(self, n_in, n_out):
        self.weight = np.zeros((n_out, n_in), dtype=np.float32)
        self.bias = np.zeros(n_out, dtype=np.float32)

    def forward(self, x):
        return np.asarray(x) @ self.weight.T + self.bias


class GRUCell(Module):
    def __init__(self, n_in, hidden):
        self.weight_ih = np.zeros((3 * hidden, n_in), dtype=np.float32)
        self.weight_hh = np.zeros((3 * hidden, hidden), dtype=np.float32)
        self.bias_ih = np.zeros(3 * hidden, dtype=np.float32)
        self.bias_hh = np.zeros(3 * hidden, dtype=np.float32)

    def forward(self, x, h):
        gi = np.asarray(x) @ self.weight_ih.T + self.bias_ih
        gh = np.asarray(h) @ self.weight_hh.T + self.bias_hh
        i_r, i_z, i_n = np.split(gi, 3, axis=-1)
        h_r, h_z, h_n = np.split(gh, 3, axis=-1)
        r = 1 / (1 + np.exp(-(i_r + h_r)))
        z = 1 / (1 + np.exp(-(i_z + h_z)))
        n = np.tanh(i_n + r * h_n)
        return (1 - z) * n + z * np.asarray(h)

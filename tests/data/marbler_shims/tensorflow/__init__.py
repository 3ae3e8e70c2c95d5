"""MARBLER's TensorBoard logging (``tf.device``, ``tf.summary``) as no-ops: the tests run its scenarios with their
own configs, which log; nothing is written (tests only)."""
from contextlib import nullcontext
from types import SimpleNamespace


def device(name):
    return nullcontext()


class _Writer:
    def as_default(self):
        return nullcontext()


summary = SimpleNamespace(create_file_writer=lambda path: _Writer(), text=lambda *a, **k: None,
                          scalar=lambda *a, **k: None)

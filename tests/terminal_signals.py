"""Ctrl-C as in a terminal, for the tests that send SIGINT.

A command started in the background by a non-interactive shell (``cmd &``, as CI scripts and
``nohup`` do) inherits SIGINT *ignored*, and Python then leaves it ignored: a SIGINT sent to such a
test process, or to a subprocess it starts, does nothing.  The tests that send SIGINT set its
terminal behaviour first (Python's ``KeyboardInterrupt``), so they test the same thing wherever
they run.
"""

import contextlib
import signal


def sigint_default() -> None:
    """``preexec_fn`` of a subprocess: SIGINT back to its default action, so the child's Python
    raises KeyboardInterrupt on it (and the processes it starts inherit that)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@contextlib.contextmanager
def sigint_raises():
    """In this process: SIGINT raises KeyboardInterrupt inside the block; the previous handler
    (ignored, under a background shell) is restored after it."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)

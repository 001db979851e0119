"""Ctrl-C during any long call raises KeyboardInterrupt, promptly (issue 38): never a
ValueError (``NumericalError``, ``InputError``) that an ``except ValueError`` would swallow."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

# Each call runs for tens of seconds uninterrupted.
LONG_CALLS = {
    "simulate": "twv.simulate(m, t_end=1000.0, h=1e-5, sample=0.01)",
    "lyapunov": "twv.lyapunov(m, x0=[0.1, 0, 0, 0, 0, 0, 0, 0], iterations=200000)",
    "ride": "twv.ride(m, t_end=1000.0, h=1e-5, sample=0.01)",
    "steady": "twv.steady(twv.Model('whipple'), speed='0:9.9:0.0001')",
}


@pytest.mark.parametrize("call", sorted(LONG_CALLS))
def test_ctrl_c_raises_keyboard_interrupt_from_every_long_call(call):
    script = textwrap.dedent(
        f"""
        import sys, twv
        m = twv.Model("vehicle8")
        print("start", flush=True)
        try:
            {LONG_CALLS[call]}
        except ValueError as e:
            print("ValueError", e, flush=True)
            sys.exit(5)
        except KeyboardInterrupt:
            print("interrupted", flush=True)
            sys.exit(7)
        print("finished", flush=True)
        """
    )
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "start"
    time.sleep(1.5)
    sent = time.monotonic()
    os.kill(proc.pid, signal.SIGINT)
    out, _ = proc.communicate(timeout=60)
    assert proc.returncode == 7, out
    assert "interrupted" in out
    # Within a second of the signal (and the interpreter's exit).
    assert time.monotonic() - sent < 3.0

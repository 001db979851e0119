"""A sweep's shards on an executor the user already has — a thread pool, a process pool, a
local Dask cluster — give the points of the in-process sweep, bit for bit; Ctrl-C stops a long
call promptly with KeyboardInterrupt."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import pytest

import twv

GRID = {"kp": (0.0, 8000.0, 8), "kd": (0.0, 4000.0, 6), "metric": "max-lyapunov"}


@pytest.fixture(scope="module")
def reference(vehicle8):
    return twv.sweep(vehicle8, **GRID)


def test_thread_pool(vehicle8, reference):
    with ThreadPoolExecutor(max_workers=2) as pool:
        assert twv.sweep(vehicle8, executor=pool, shards=5, **GRID).points == reference.points


def test_process_pool_pickles_the_model(reference):
    model = twv.Model("vehicle8", params={"m2": 8.0})
    with ProcessPoolExecutor(max_workers=2) as pool:
        assert twv.sweep(model, executor=pool, shards=3, **GRID).points == reference.points


def test_local_dask_cluster(vehicle8, reference):
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        result = twv.sweep(vehicle8, executor=client, shards=4, **GRID)
    assert result.points == reference.points
    assert result.value.shape == (1, 6, 8)


def test_ctrl_c_interrupts_a_long_sweep():
    script = textwrap.dedent(
        """
        import sys, twv
        print("start", flush=True)
        try:
            twv.sweep(twv.Model("vehicle8"), kp=(0, 8000, 400), kd=(0, 4000, 400))
        except KeyboardInterrupt:
            print("interrupted", flush=True)
            sys.exit(7)
        """
    )
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "start"
    time.sleep(1.0)
    sent = time.monotonic()
    os.kill(proc.pid, signal.SIGINT)
    out, _ = proc.communicate(timeout=60)
    assert proc.returncode == 7, out
    assert "interrupted" in out
    # Stopped at the next chunk boundary, not after the 160 000-point map.
    assert time.monotonic() - sent < 20

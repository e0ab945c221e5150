"""A study submitted to a running Ray cluster (``--address``) survives a killed worker with the serial rows.

A head node (``ray start --head --block``, 2 CPUs, its own temporary folder and free ports) runs in a
process group of its own; the study's one job (checkpoints every epoch) runs on it; once the job has
written a checkpoint its worker process (``ray::run_one``, in the head's process tree) is killed. Ray
retries the task, the job resumes from its checkpoint, and the rows equal a serial run's. The head's
process group is stopped in a ``finally`` (not ``ray stop``, which stops every Ray instance of the machine).
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import pandas as pd
import pytest

from tests.helpers.toy_study import toy_settings, toy_spec
from twodrl_bench.runner import run_study

ray = pytest.importorskip("ray", reason="Ray is absent (extra 'cluster')")
psutil = pytest.importorskip("psutil")
ROOT = Path(__file__).resolve().parents[2]


def free_ports(n: int) -> list[int]:
    sockets = [socket.socket() for _ in range(n)]
    for s in sockets:
        s.bind(("127.0.0.1", 0))
    ports = [s.getsockname()[1] for s in sockets]
    for s in sockets:
        s.close()
    return ports


def wait_for_port(port: int, head: subprocess.Popen, timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if head.poll() is not None:
            raise RuntimeError(f"ray start exited with {head.returncode}")
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.2)
    raise TimeoutError(f"the Ray head did not listen on {port} within {timeout} s")


def kill_job_worker(head: int, folder: Path, killed: list[int], stop: threading.Event) -> None:
    """Once the job has a checkpoint, SIGKILL the worker running it: a process of the head's tree (none of another
    Ray instance) titled ``ray::run_one`` (:func:`twodrl_bench.backends.run_one`)."""
    checkpoint = folder / "checkpoints" / "twoda2c_seed0.pkl"
    while not stop.is_set() and not checkpoint.exists():
        time.sleep(0.05)
    for proc in psutil.Process(head).children(recursive=True):
        try:
            if proc.cmdline() and proc.cmdline()[0].startswith("ray::run_one"):
                os.kill(proc.pid, signal.SIGKILL)
                killed.append(proc.pid)
        except psutil.NoSuchProcess:
            continue


@pytest.mark.skipif(shutil.which("ray") is None, reason="the ray command is absent")
def test_a_study_on_a_cluster_survives_a_killed_worker_with_the_serial_rows(tmp_path) -> None:
    settings = toy_settings(tmp_path / "settings")
    protocol = {"epochs": 6, "learn_episodes": 60, "test_episodes": 4, "checkpoint_every": 1}
    spec = toy_spec(settings, seeds=[0], protocol=protocol, arms={"twoda2c": toy_spec(settings)["arms"]["twoda2c"]})
    serial = pd.read_csv(run_study(spec, tmp_path / "serial", "serial", report=False) / "rows.csv")

    gcs, node, objects, client, low = free_ports(5)
    temp = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths must fit 107 characters
    command = ["ray", "start", "--head", "--block", "--num-cpus", "2", "--temp-dir", temp, "--port", str(gcs)]
    command += ["--node-manager-port", str(node), "--object-manager-port", str(objects)]
    command += ["--ray-client-server-port", str(client), "--min-worker-port", str(low + 1)]
    command += ["--max-worker-port", str(low + 40), "--include-dashboard", "false", "--disable-usage-stats"]
    command += ["--object-store-memory", str(80 * 2**20), "--node-ip-address", "127.0.0.1"]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1", "RAY_USAGE_STATS_ENABLED": "0"}
    head = subprocess.Popen(command, env=env, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    killed: list[int] = []
    stop = threading.Event()
    try:
        wait_for_port(gcs, head, 40)
        args = (head.pid, tmp_path / "cluster", killed, stop)
        killer = threading.Thread(target=kill_job_worker, args=args, daemon=True)
        killer.start()
        folder = run_study(spec, tmp_path / "cluster", "ray", address=f"127.0.0.1:{gcs}", report=False)
        stop.set()
        killer.join(5)
    finally:
        stop.set()
        if ray.is_initialized():
            ray.shutdown()
        os.killpg(head.pid, signal.SIGTERM)
        try:
            head.wait(15)
        except subprocess.TimeoutExpired:
            os.killpg(head.pid, signal.SIGKILL)
            head.wait(5)
        shutil.rmtree(temp, ignore_errors=True)
    assert killed, "no Ray worker ran the job when its first checkpoint appeared"
    rows = pd.read_csv(folder / "rows.csv")
    pd.testing.assert_frame_equal(rows.drop(columns="wall_s"), serial.drop(columns="wall_s"), check_exact=True)

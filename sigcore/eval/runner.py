"""Running an evaluation's episodes: K at once on this machine, or as Ray tasks on a cluster; each row recorded as
its episode ends.

Local episodes run from K threads of this process; each thread only starts and watches its episode's processes.
On Ray each episode is a task that declares the CPUs it needs; it runs the episode in a temporary folder of its
worker and sends the row and the files (logs, results) back, so the driver's folder holds them whatever machine ran
them.
"""

from __future__ import annotations

import logging
import os
import tempfile
import threading
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from dataclasses import replace
from typing import Any

from .episode import INTERRUPTED, EpisodeRow, EpisodeSpec, run_episode
from .exceptions import EvalError

MAX_LOG = 5 * 2**20
"""A log longer than this comes back from a Ray worker as its last bytes only [bytes]."""

FILES = ("sim.log", "solution.log", "result.json")
"""An episode's files."""

LOCAL_ONLY = "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"
"""Set to 0, Ray keeps a node on the loopback address (``ray start --node-ip-address=127.0.0.1`` alone binds to the
machine's network address instead); the cluster and the driver both need it."""

LOOPBACK = ("127.0.0.1", "localhost")

OnRow = Callable[[EpisodeRow], None]


def run_local(specs: Iterable[EpisodeSpec], workers: int, on_row: OnRow) -> None:
    """Run ``specs``, ``workers`` at once; ``on_row`` gets each row (in this thread) as its episode ends.

    On KeyboardInterrupt every running episode is stopped (its rows are not given: ``--resume`` runs them again),
    none is started, and the interrupt goes on.
    """
    stop = threading.Event()
    queue = list(specs)
    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="episode") as pool:
        running: set[Future[EpisodeRow]] = set()
        try:
            while queue or running:
                while queue and len(running) < workers:
                    running.add(pool.submit(run_episode, queue.pop(0), stop))
                done, running = wait(running, timeout=0.5, return_when=FIRST_COMPLETED)
                for future in done:
                    row = future.result()
                    if row.status != INTERRUPTED:
                        on_row(row)
        except BaseException:
            stop.set()  # the episodes end their processes; the pool's exit waits for them
            raise


def ray_episode(spec: EpisodeSpec) -> tuple[EpisodeRow, dict[str, bytes]]:
    """A Ray task: ``spec`` run in a temporary folder of the worker; the row and the episode's files."""
    with tempfile.TemporaryDirectory(prefix="sigcore-episode-") as tmp:
        here = replace(spec, out=tmp)
        row = run_episode(here)
        files = {}
        for name in FILES:
            path = here.folder / name
            if path.exists():
                with open(path, "rb") as f:
                    size = path.stat().st_size
                    if size > MAX_LOG:
                        f.seek(size - MAX_LOG)
                    files[name] = f.read()
    row.folder = str(spec.folder)
    return row, files


def run_ray(specs: Iterable[EpisodeSpec], address: str, cpus: float, on_row: OnRow, *,
            node_ip: str | None = None, working_dir: str | None = None,
            on_nodes: Callable[[list[dict[str, Any]]], None] | None = None) -> dict[str, Any]:
    """Run ``specs`` as Ray tasks of ``cpus`` CPUs each on the cluster at ``address``; ``on_row`` gets each row as
    its task ends (its files are written to the episode's folder here first). The cluster's nodes as Ray lists them.

    Args:
        address: The cluster (``HOST:PORT`` of its head, or ``auto``).
        cpus: CPUs each episode declares (its simulator and its solution).
        node_ip: The address this driver tells Ray it has (``127.0.0.1`` for a cluster bound to the loopback).
        working_dir: Shipped to the workers as the tasks' working folder (Ray's ``runtime_env``).
        on_nodes: Given the cluster's nodes (address, alive, CPUs) once connected, before any task starts.

    Raises:
        EvalError: Ray is not installed, or the cluster cannot be reached.
    """
    if node_ip in LOOPBACK:
        # Ray replaces a loopback address by the machine's network address unless told this (read at its import)
        os.environ[LOCAL_ONLY] = "0"
    try:
        import ray
    except ImportError:
        raise EvalError("--ray needs Ray: .venv/bin/pip install 'ray==2.60.0' (scripts/setup.sh installs it)") \
            from None
    runtime_env = {"working_dir": working_dir} if working_dir else None
    try:
        ray.init(address=address, _node_ip_address=node_ip, runtime_env=runtime_env, log_to_driver=False,
                 logging_level=logging.WARNING, configure_logging=True)
    except (ConnectionError, ValueError, RuntimeError) as e:
        raise EvalError(f"--ray {address}: cannot connect to the cluster: {e}; start one on this machine with: "
                        f"{LOCAL_ONLY}=0 ray start --head --node-ip-address=127.0.0.1 --port=6379 (then --ray "
                        "127.0.0.1:6379)") from None
    try:
        nodes = [{"address": n.get("NodeManagerAddress"), "alive": n.get("Alive"),
                  "cpus": n.get("Resources", {}).get("CPU")} for n in ray.nodes()]
        if on_nodes is not None:
            on_nodes(nodes)
        task = ray.remote(num_cpus=cpus, max_retries=0)(ray_episode)
        pending = {task.remote(spec): spec for spec in specs}
        try:
            while pending:
                done, _ = ray.wait(list(pending), num_returns=1, timeout=0.5)
                for ref in done:
                    spec = pending.pop(ref)
                    try:
                        row, files = ray.get(ref)
                    except ray.exceptions.RayError as e:  # the worker died, the task could not run
                        first = str(e).splitlines()[0] if str(e) else ""
                        row = EpisodeRow(spec.index, spec.seed, "simulator_error", False, folder=str(spec.folder),
                                         reason=f"the Ray task failed: {e.__class__.__name__}: {first}")
                        files = {}
                    spec.folder.mkdir(parents=True, exist_ok=True)
                    for name, data in files.items():
                        (spec.folder / name).write_bytes(data)
                    on_row(row)
        except BaseException:
            for ref in pending:  # the tasks get KeyboardInterrupt: each ends its processes
                ray.cancel(ref)
            raise
        return {"nodes": nodes}
    finally:
        ray.shutdown()

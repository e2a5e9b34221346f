"""``ego sweep`` and ``ego tune`` on a multi-node Ray cluster, on this machine (issue 23).

One ``ray.cluster_utils.Cluster`` per module - a head and two worker nodes, one CPU each, all
on 127.0.0.1 - joined by ``ego ... --engine ray --address``:

* a sweep completes with every row, and each row names the node (its Ray node id) that ran it;
* a worker node removed mid-sweep costs only the runs it had in flight one retry;
* SIGKILL of the sweep leaves none of its processes on any node;
* ``ego tune --cost sumo --engine ray --address`` runs on the same cluster.

Also, without a cluster: an address where nothing (or something else) listens is one line
in seconds, and a SIGKILLed sweep on a private Ray instance leaves no Ray process behind.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import psutil
import pyarrow.parquet as pq
import pytest

#: a three-node Ray cluster takes a minute to start and stop: ``-m long`` runs these
pytestmark = pytest.mark.long

SPEC = (
    'scenario = "emergency-brake"\ncontrollers = ["pid"]\nseeds = {seeds}\n[set]\nduration = {duration}\n'
    "[grid]\nego_speed = [18, 20, 22, 24]\n"
)


@pytest.fixture(scope="module")
def cluster():
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    from ray.cluster_utils import Cluster

    c = Cluster(
        initialize_head=True,
        head_node_args={
            "num_cpus": 1,
            "node_ip_address": "127.0.0.1",
            "include_dashboard": False,
        },
    )
    workers = [c.add_node(num_cpus=1, node_ip_address="127.0.0.1") for _ in range(2)]
    c.wait_for_nodes()
    yield c, workers
    c.shutdown()


def _ego(*args: str, cwd: Path, **kw) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "ego", *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        **kw,
    )


def _node_ids(c) -> set[str]:
    return {n.node_id for n in [c.head_node, *c.worker_nodes]}


def test_a_sweep_on_three_nodes_has_every_row_with_its_node(cluster, tmp_path):
    c, _ = cluster
    (tmp_path / "s.toml").write_text(SPEC.format(seeds=3, duration=3))
    proc = _ego(
        "sweep",
        "s.toml",
        "--out",
        "o",
        "--engine",
        "ray",
        "--address",
        c.address,
        "--record",
        "none",
        cwd=tmp_path,
    )
    _out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err[-3000:]
    table = pq.read_table(tmp_path / "o" / "results.parquet").to_pydict()
    assert len(table["run_id"]) == 12 and len(set(table["run_id"])) == 12
    assert set(table["node"]) <= _node_ids(c)
    assert len(set(table["node"])) >= 2  # spread over nodes, each named by its id
    assert all(len(n) == 56 for n in table["node"])  # a Ray node id, not a host name
    assert set(table["attempts"]) == {1}
    assert "error" not in table["status"]


def test_losing_a_worker_node_mid_sweep_costs_only_its_runs_one_retry(cluster, tmp_path):
    c, workers = cluster
    # 80 runs of 10 s (~3 s of work a node): with 24 runs of 3 s the head and the other
    # node could finish them all while the victim's Ray worker was still starting (seen on a
    # slower machine, twice)
    (tmp_path / "s.toml").write_text(SPEC.format(seeds=20, duration=10))
    proc = _ego(
        "sweep",
        "s.toml",
        "--out",
        "o",
        "--engine",
        "ray",
        "--address",
        c.address,
        "--record",
        "none",
        cwd=tmp_path,
    )
    victim = workers[0]
    lines: list[str] = []

    def read() -> None:
        for line in proc.stderr:
            lines.append(line)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and sum(" runs, " in line for line in lines) < 4:
        time.sleep(0.1)
    assert sum(" runs, " in line for line in lines) >= 4, "".join(lines)[-2000:]
    # remove it while it runs one of the sweep's runs (a node between two runs holds none)
    while time.monotonic() < deadline and proc.poll() is None and not _running_a_task(victim):
        time.sleep(0.005)
    assert proc.poll() is None, "the sweep ended before the node ran a task: " + "".join(lines)[-2000:]
    c.remove_node(victim)  # its raylet and workers die with the runs in flight
    proc.wait(timeout=300)
    reader.join(timeout=10)
    assert proc.returncode == 0, "".join(lines)[-3000:]
    table = pq.read_table(tmp_path / "o" / "results.parquet").to_pydict()
    assert len(table["run_id"]) == 80 and len(set(table["run_id"])) == 80
    assert "error" not in table["status"]
    retried = [i for i, a in enumerate(table["attempts"]) if a == 2]
    # only the runs the lost node had in flight (at most 2 per CPU: ray_engine.IN_FLIGHT_PER_WORKER)
    assert 1 <= len(retried) <= 2, table["attempts"]
    assert all(table["node"][i] != victim.node_id for i in retried)
    assert max(table["attempts"]) == 2
    c.add_node(num_cpus=1, node_ip_address="127.0.0.1")  # back to three nodes for the next tests
    workers[0] = next(n for n in c.worker_nodes if n is not workers[1])
    c.wait_for_nodes()


def _running_a_task(node) -> bool:
    """A Ray worker of ``node`` is running a task now: Ray titles an idle worker ``ray::IDLE``
    and a busy one ``ray::<function>`` (its agents ``ray::...Agent``)."""
    raylet = psutil.Process(node.all_processes["raylet"][0].process.pid)
    for child in raylet.children(recursive=True):
        try:
            title = child.cmdline()
        except psutil.Error:
            continue
        name = title[0] if title else ""
        if name.startswith("ray::") and name.split()[0] != "ray::IDLE" and not name.split()[0].endswith("Agent"):
            return True
    return False


def _job_processes(c, before: set[int]) -> list[psutil.Process]:
    """Processes of the cluster ``c`` that ran ego's tasks (its raylets' workers with ego
    imported) and are not from before. Only this cluster's workers count: an ``ego run`` or a
    Ray of another test file (pytest -n) running meanwhile is not the sweep's."""
    found = []
    for node in c.list_all_nodes():
        try:
            workers = psutil.Process(node.all_processes["raylet"][0].process.pid).children(recursive=True)
        except psutil.Error:
            continue
        for p in workers:
            if p.pid in before:
                continue
            try:
                maps = Path(f"/proc/{p.pid}/maps").read_text()
            except OSError:
                continue
            if "/ego/" in maps and ("libsumo" in maps or "_native" in maps):
                found.append(p)
    return found


def test_a_sigkilled_sweep_leaves_none_of_its_processes_on_any_node(cluster, tmp_path):
    c, _ = cluster
    (tmp_path / "s.toml").write_text(SPEC.format(seeds=10, duration=3))
    before = {p.pid for p in psutil.process_iter()}
    proc = _ego(
        "sweep",
        "s.toml",
        "--out",
        "o",
        "--engine",
        "ray",
        "--address",
        c.address,
        "--record",
        "none",
        cwd=tmp_path,
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not _job_processes(c, before):
        time.sleep(0.2)
    assert _job_processes(c, before), "no task of the sweep started"
    descendants = psutil.Process(proc.pid).children(recursive=True)
    proc.kill()
    proc.wait(timeout=30)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and (
        _job_processes(c, before) or any(d.is_running() and d.status() != "zombie" for d in descendants)
    ):
        time.sleep(0.5)
    assert not _job_processes(c, before), [p.pid for p in _job_processes(c, before)]
    assert not [d for d in descendants if d.is_running() and d.status() != "zombie"]


@pytest.mark.benchmark  # about a minute: run with -m benchmark
def test_tune_with_sumo_costs_on_the_cluster(cluster, tmp_path):
    c, _ = cluster
    proc = _ego(
        "tune",
        "lane-centering",
        "--quick",
        "--cost",
        "sumo",
        "--engine",
        "ray",
        "--address",
        c.address,
        "--duration",
        "2",
        "--out",
        "g.json",
        cwd=tmp_path,
    )
    _out, err = proc.communicate(timeout=600)
    assert proc.returncode == 0, err[-3000:]
    preset = json.loads((tmp_path / "g.json").read_text())
    assert preset["gains"] and all(isinstance(g, float) for g in preset["gains"].values())


# -- without a cluster ------------------------------------------------------------------------------------


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("where", ["nothing", "refused-http", "unknown-host", "blackhole"])
def test_an_address_without_a_ray_head_is_one_line_within_seconds(where, tmp_path):
    (tmp_path / "s.toml").write_text(SPEC.format(seeds=1, duration=3))
    server = None
    if where == "nothing":
        address, needle = "127.0.0.1:1", "Connection refused"
    elif where == "refused-http":
        port = _free_port()
        server = subprocess.Popen(
            [sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        for _ in range(100):
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
                break
            except OSError:
                time.sleep(0.1)
        address, needle = f"127.0.0.1:{port}", "not a Ray head"
    elif where == "unknown-host":
        address, needle = "no-such-host.invalid:6379", "unknown host"
    else:
        address, needle = "192.0.2.254:6379", ""  # TEST-NET: no answer or unreachable
    try:
        t0 = time.monotonic()
        proc = _ego(
            "sweep",
            "s.toml",
            "--out",
            "o",
            "--engine",
            "ray",
            "--address",
            address,
            cwd=tmp_path,
        )
        _out, err = proc.communicate(timeout=60)
        assert time.monotonic() - t0 < 15
    finally:
        if server is not None:
            server.kill()
            server.wait()
    assert proc.returncode == 2, err
    assert err.startswith("ego: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    assert address in err and needle in err
    assert not (tmp_path / "o").exists()


def test_a_sigkilled_sweep_on_a_private_ray_leaves_no_ray_process(tmp_path):
    (tmp_path / "s.toml").write_text(SPEC.format(seeds=20, duration=3))
    proc = _ego(
        "sweep",
        "s.toml",
        "--out",
        "o",
        "--engine",
        "ray",
        "--jobs",
        "1",
        "--record",
        "none",
        cwd=tmp_path,
    )
    deadline = time.monotonic() + 120
    ray_started = []
    while time.monotonic() < deadline:
        kids = psutil.Process(proc.pid).children(recursive=True)
        names = " ".join(" ".join(k.cmdline()) for k in kids if k.is_running())
        if "DashboardAgent" in names or "RuntimeEnvAgent" in names or "raylet" in names:
            if (tmp_path / "o" / ".ego.lock").exists():
                ray_started = kids
                break
        time.sleep(0.2)
    assert ray_started, "the private Ray instance did not start"
    time.sleep(2.0)  # tasks running
    ray_started = psutil.Process(proc.pid).children(recursive=True)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)
    deadline = time.monotonic() + 30
    alive = ray_started
    while time.monotonic() < deadline:
        alive = [k for k in ray_started if k.is_running() and k.status() != "zombie"]
        if not alive:
            break
        time.sleep(0.5)
    assert not alive, [" ".join(k.cmdline())[:80] for k in alive]

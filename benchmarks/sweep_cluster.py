"""solidshell sweep on dask.distributed: speed-up, a hand-started cluster, and fault injection.

One 16-run sweep (square-pedestal 6x2x4, static, 16 randomly perturbed starts of 0.3 cm) is run

1. ``speed``     on a 1-worker and a 2-worker LocalCluster, in this one invocation: the wall-time
                 ratio, with the load average before and after each (the machine is shared);
2. ``scheduler`` on a hand-started ``dask scheduler`` + 2 ``dask worker`` processes on 127.0.0.1,
                 addressed by ``solidshell sweep --scheduler``: its ledger must equal the local
                 cluster's (DC, folds, residual, r(theta), bit for bit);
3. ``kill-worker`` there again, SIGKILLing a worker process (by its pid) while it runs a task:
                 the run is retried elsewhere and the sweep completes;
4. ``kill-client`` the CLI client SIGKILLed mid-sweep and started again: no duplicate, no lost run.

Run:  python benchmarks/sweep_cluster.py [speed scheduler kill-worker kill-client] [--out DIR]
Writes DIR/sweep_cluster.json and .md (default benchmarks/out/sweep_cluster).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
PY = sys.executable
DASK = str(Path(PY).with_name("dask"))
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}

SWEEP = """
name = "bench-16"
description = "16 perturbed starts of square-pedestal {mesh}, static"
scene = "square-pedestal"
mesh = "{mesh}"
solver = "static"
[set]
"perturbation.amplitude" = 0.3
[grid]
"perturbation.seed" = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]
"""

COMPARE = ("drape_coefficient", "fold_count", "fold_angles_deg", "residual", "radius_profile", "converged", "stable")
"""Columns that must agree bit for bit.  min_tangent_eigenvalue is compared to 1e-12 relative: ARPACK
(scipy eigsh) starts from a random vector, so the last digits of the eigenvalue vary from call to
call while the state itself does not."""


def same(a, b) -> list:
    """[(key, column)] where two ledgers differ (a key missing from b counts)."""
    diff = [(k, c) for k in a for c in COMPARE if k not in b or a[k][c] != b[k][c]]
    for k in a:
        if k in b:
            x, y = a[k]["min_tangent_eigenvalue"], b[k]["min_tangent_eigenvalue"]
            if (x is None) != (y is None) or x is not None and abs(x - y) > 1e-12 * abs(x):
                diff.append((k, "min_tangent_eigenvalue"))
    return diff


def load():
    return [round(x, 2) for x in os.getloadavg()]


def rows(out, spec):
    from solidshell.sweep.ledger import Ledger

    return {r["key"]: r for r in Ledger(out, spec).read().to_pylist()}


def steady(out, spec) -> dict:
    """Throughput once every worker has finished its first run (numba loading, imports: the
    worker's warm-up): runs recorded after that moment / the time they took [runs/s]."""
    from datetime import datetime

    rs = sorted(rows(out, spec).values(), key=lambda r: r["finished_at"])
    ts = [datetime.fromisoformat(r["finished_at"]) for r in rs]
    first = {}
    for r, t in zip(rs, ts):
        first.setdefault(r["worker"], t)
    t0 = max(first.values())
    n = sum(1 for t in ts if t > t0)
    span = (ts[-1] - t0).total_seconds()
    return {
        "warm_up_run_wall_s": sorted(round(r["wall_time_s"], 1) for r in rs)[-len(first) :],
        "steady_runs": n,
        "steady_span_s": span,
        "steady_runs_per_s": round(n / span, 4) if span else None,
    }


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class HandCluster:
    """``dask scheduler`` + n ``dask worker`` processes on 127.0.0.1 (started and stopped by pid)."""

    def __init__(self, n=2, log_dir=None, sessions=False):
        self.port = free_port()
        self.addr = f"tcp://127.0.0.1:{self.port}"
        log_dir = Path(log_dir or "/tmp")
        self.logs = [open(log_dir / f"dask-{k}.log", "w") for k in ["scheduler"] + [f"worker{i}" for i in range(n)]]
        self.procs = [
            subprocess.Popen(
                [
                    DASK,
                    "scheduler",
                    "--host",
                    "127.0.0.1",
                    "--port",
                    str(self.port),
                    "--dashboard-address",
                    "127.0.0.1:0",
                ],
                env=ENV,
                stdout=self.logs[0],
                stderr=subprocess.STDOUT,
            )
        ]
        time.sleep(3)
        for i in range(n):
            self.procs.append(
                subprocess.Popen(
                    [
                        DASK,
                        "worker",
                        self.addr,
                        "--nthreads",
                        "1",
                        "--nworkers",
                        "1",
                        "--host",
                        "127.0.0.1",
                        "--dashboard-address",
                        "127.0.0.1:0",
                        "--name",
                        f"w{i}",
                    ],
                    env=ENV,
                    stdout=self.logs[i + 1],
                    stderr=subprocess.STDOUT,
                    start_new_session=sessions,
                )
            )
        from distributed import Client

        self.client = Client(self.addr, timeout="60s")
        self.client.wait_for_workers(n, timeout=120)

    def worker_pids(self) -> dict:
        return self.client.run(os.getpid)  # {worker address: pid of the worker process}

    def close(self):
        self.client.close()
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
        for p in self.procs:
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                p.kill()
        for f in self.logs:
            f.close()


def speed(spec, out, rep):
    """1, 2, 2, 1 workers (ABBA: a load that drifts linearly during the four sweeps cancels out)."""
    from solidshell.sweep.engine import Cluster, run_sweep

    res = {}
    for n, tag in ((1, "local1"), (2, "local2"), (2, "local2b"), (1, "local1b")):
        before = load()
        t0 = time.perf_counter()
        r = run_sweep(spec, out / tag, Cluster(workers=n), progress=False)
        wall = time.perf_counter() - t0
        assert r.recorded == 16 and not r.failed, r
        rw = rows(out / tag, spec).values()
        res[tag] = {
            "workers": n,
            "wall_s": round(wall, 1),
            "load_before": before,
            "load_after": load(),
            "sum_run_wall_s": round(sum(x["wall_time_s"] for x in rw), 1),
            "sum_run_cpu_s": round(sum(x["cpu_time_s"] for x in rw), 1),
            **steady(out / tag, spec),
        }
        print(f"{n} worker(s): {wall:.1f} s (load {before} -> {res[tag]['load_after']})", flush=True)
    a, b = rows(out / "local1", spec), rows(out / "local2", spec)
    t1 = res["local1"]["wall_s"] + res["local1b"]["wall_s"]
    t2 = res["local2"]["wall_s"] + res["local2b"]["wall_s"]
    thr = lambda *t: sum(res[x]["steady_runs_per_s"] for x in t)  # noqa: E731
    rep["speed"] = {
        **res,
        "ratio_1_over_2": round(t1 / t2, 3),
        "steady_throughput_ratio_2_over_1": round(thr("local2", "local2b") / thr("local1", "local1b"), 3),
        "ratio_first_pair": round(res["local1"]["wall_s"] / res["local2"]["wall_s"], 3),
        "results_identical_1_vs_2": not same(a, b),
    }


def speed_sessions(spec, out, rep):
    """As ``speed``, on hand-started clusters whose workers each run in their own session.

    Linux's autogroup scheduler (kernel.sched_autogroup_enabled = 1 here) shares the CPUs fairly
    between *sessions*, not processes: on a busy machine every process of one session -- a
    LocalCluster's client, scheduler and workers -- shares that session's one slice, so a second
    local worker cannot add CPU time.  Workers started apart (as on a real cluster, one per
    machine or per login) each get a slice; this measures the sweep's scaling in that setting."""
    from solidshell.sweep.engine import Cluster, run_sweep

    res = {}
    for n, tag in ((1, "sess1"), (2, "sess2"), (2, "sess2b"), (1, "sess1b")):
        hc = HandCluster(n, out, sessions=True)
        try:
            before = load()
            t0 = time.perf_counter()
            r = run_sweep(spec, out / tag, Cluster(scheduler=hc.addr), progress=False)
            wall = time.perf_counter() - t0
        finally:
            hc.close()
        assert r.recorded == 16 and not r.failed, r
        rw = rows(out / tag, spec).values()
        res[tag] = {
            "workers": n,
            "wall_s": round(wall, 1),
            "load_before": before,
            "load_after": load(),
            "sum_run_cpu_s": round(sum(x["cpu_time_s"] for x in rw), 1),
            **steady(out / tag, spec),
        }
        print(f"{n} worker(s) in own sessions: {wall:.1f} s (load {before} -> {res[tag]['load_after']})", flush=True)
    t1 = res["sess1"]["wall_s"] + res["sess1b"]["wall_s"]
    t2 = res["sess2"]["wall_s"] + res["sess2b"]["wall_s"]
    thr = lambda *t: sum(res[x]["steady_runs_per_s"] for x in t)  # noqa: E731
    rep["speed_sessions"] = {
        **res,
        "ratio_1_over_2": round(t1 / t2, 3),
        "steady_throughput_ratio_2_over_1": round(thr("sess2", "sess2b") / thr("sess1", "sess1b"), 3),
        "results_identical_1_vs_2": not same(rows(out / "sess1", spec), rows(out / "sess2", spec)),
    }


def scheduler(spec, out, rep):
    hc = HandCluster(2, out)
    try:
        pids = hc.worker_pids()
        cmd = [
            PY,
            "-m",
            "solidshell",
            "sweep",
            str(out / "bench.toml"),
            "--scheduler",
            hc.addr,
            "--out",
            str(out / "hand"),
            "--no-progress",
        ]
        t0 = time.perf_counter()
        p = subprocess.run(cmd, env=ENV, cwd=ROOT, capture_output=True, text=True)
        wall = time.perf_counter() - t0
    finally:
        hc.close()
    a, b = rows(out / "local2", spec), rows(out / "hand", spec)
    diff = same(a, b)
    rep["scheduler"] = {
        "address": hc.addr,
        "worker_pids": pids,
        "exit": p.returncode,
        "wall_s": round(wall, 1),
        "stdout": p.stdout.strip().splitlines(),
        "runs": len(b),
        "identical_to_local_cluster": not diff,
        "differences": diff[:10],
        "workers_used": sorted({r["worker"] for r in b.values()}),
    }
    print(json.dumps(rep["scheduler"], indent=1), flush=True)


def kill_worker(spec, out, rep):
    import threading

    from solidshell.sweep.engine import Cluster, run_sweep

    hc = HandCluster(2, out)
    info = {}

    def executing(dask_worker):  # runs on the worker: the tasks it is running
        return sorted(str(ts.key) for ts in dask_worker.state.executing)

    def killer():
        # once 3 runs are recorded, wait for a worker to be 4 s into a run, then SIGKILL its process
        deadline = time.time() + 1800
        while time.time() < deadline:
            if len(list((out / "killw" / "ledger").glob("*.parquet"))) >= 3:
                running = {w: ks for w, ks in hc.client.run(executing).items() if ks}
                if running:
                    w, ks = next(iter(running.items()))
                    time.sleep(4.0)
                    if hc.client.run(executing, workers=[w]).get(w) != ks:
                        continue  # that run ended meanwhile: pick again
                    pid = hc.worker_pids()[w]
                    info.update(
                        worker=w,
                        pid=pid,
                        task=ks[0],
                        killed_at=time.strftime("%H:%M:%S"),
                        recorded_before=len(list((out / "killw" / "ledger").glob("*.parquet"))),
                    )
                    os.kill(pid, signal.SIGKILL)
                    return
            time.sleep(0.5)

    th = threading.Thread(target=killer, daemon=True)
    try:
        th.start()
        t0 = time.perf_counter()
        r = run_sweep(spec, out / "killw", Cluster(scheduler=hc.addr), progress=False)
        wall = time.perf_counter() - t0
        th.join(5)
        after = hc.worker_pids()
    finally:
        hc.close()
    b = rows(out / "killw", spec)
    key = info.get("task", "").rsplit("-", 1)[-1]
    a = rows(out / "local2", spec)
    rep["kill_worker"] = {
        **info,
        "recorded": r.recorded,
        "failed": r.failed,
        "wall_s": round(wall, 1),
        "workers_after": after,
        "killed_run_recorded": key in b,
        "killed_run_finished_on": b.get(key, {}).get("worker"),
        "all_16_once": sorted(b) == sorted(x.key for x in spec.runs),
        "identical_to_local_cluster": not same(a, b),
    }
    print(json.dumps(rep["kill_worker"], indent=1), flush=True)


def kill_client(spec, out, rep):
    hc = HandCluster(2, out)
    led = out / "killc" / "ledger"
    cmd = [
        PY,
        "-m",
        "solidshell",
        "sweep",
        str(out / "bench.toml"),
        "--scheduler",
        hc.addr,
        "--out",
        str(out / "killc"),
        "--no-progress",
    ]
    try:
        with open(out / "client1.log", "w") as log:
            p = subprocess.Popen(cmd, env=ENV, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT)
            while len(list(led.glob("*.parquet"))) < 5 and p.poll() is None:
                time.sleep(0.3)
            time.sleep(2.0)  # mid-run: tasks are running on both workers
            processing = sum(len(v) for v in hc.client.processing().values())
            os.kill(p.pid, signal.SIGKILL)
            p.wait()
        n_killed = len(list(led.glob("*.parquet")))
        time.sleep(3.0)
        p2 = subprocess.run(cmd, env=ENV, cwd=ROOT, capture_output=True, text=True)
    finally:
        hc.close()
    b = rows(out / "killc", spec)
    a = rows(out / "local2", spec)
    parts = sorted(x.name for x in led.glob("*.parquet"))
    rep["kill_client"] = {
        "recorded_when_killed": n_killed,
        "tasks_processing_when_killed": processing,
        "restart_exit": p2.returncode,
        "restart_stdout": p2.stdout.strip().splitlines(),
        "parts": len(parts),
        "unique_keys": len(set(parts)),
        "all_16_once": sorted(b) == sorted(x.key for x in spec.runs),
        "identical_to_local_cluster": not same(a, b),
    }
    print(json.dumps(rep["kill_client"], indent=1), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("parts", nargs="*", default=["speed", "scheduler", "kill-worker", "kill-client"])
    ap.add_argument("--out", default=str(HERE / "out" / "sweep_cluster"))
    ap.add_argument("--recompute", action="store_true", help="recompute the speed figures from the ledgers kept")
    ap.add_argument(
        "--mesh",
        default="6x2x4",
        help="the pedestal mesh of each run (a larger one weighs the "
        "runs against the workers' fixed start-up: imports and the kernel cache, ~2 s each)",
    )
    a = ap.parse_args()
    out = Path(a.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    (out / "bench.toml").write_text(SWEEP.format(mesh=a.mesh))
    from solidshell.sweep import load_spec

    spec = load_spec(out / "bench.toml")
    rep_path = out / "sweep_cluster.json"
    rep = json.loads(rep_path.read_text()) if rep_path.is_file() else {}
    rep["cpus"] = os.cpu_count()
    dirs = {
        "speed": ["local1", "local2", "local2b", "local1b"],
        "speed-sessions": ["sess1", "sess2", "sess2b", "sess1b"],
        "scheduler": ["hand"],
        "kill-worker": ["killw"],
        "kill-client": ["killc"],
    }
    if a.recompute:
        for key, tags in (
            ("speed", ("local1", "local2", "local2b", "local1b")),
            ("speed_sessions", ("sess1", "sess2", "sess2b", "sess1b")),
        ):
            if key in rep:
                for t in tags:
                    rep[key][t].update(steady(out / t, spec))
                thr = lambda *t: sum(rep[key][x]["steady_runs_per_s"] for x in t)  # noqa: E731
                rep[key]["steady_throughput_ratio_2_over_1"] = round(thr(tags[1], tags[2]) / thr(tags[0], tags[3]), 3)
        a.parts = []
        rep_path.write_text(json.dumps(rep, indent=1, default=str))
    for part in a.parts:
        for d in dirs[part]:
            shutil.rmtree(out / d, ignore_errors=True)  # a fresh sweep, not a resumed one
        {
            "speed": speed,
            "speed-sessions": speed_sessions,
            "scheduler": scheduler,
            "kill-worker": kill_worker,
            "kill-client": kill_client,
        }[part](spec, out, rep)
        rep_path.write_text(json.dumps(rep, indent=1, default=str))
    write_md(rep, out / "sweep_cluster.md")
    print(f"wrote {rep_path} and sweep_cluster.md")


def write_md(rep, path):
    """The figures of sweep_cluster.json as a short table (load averages: 1, 5, 15 min)."""
    lines = [f"# solidshell sweep on dask.distributed ({rep.get('cpus')} CPUs, shared machine)", ""]
    for key, title in (("speed", "LocalCluster (one session)"), ("speed_sessions", "workers in their own sessions")):
        if key not in rep:
            continue
        r = rep[key]
        lines += [
            f"## 16-run sweep, 1 vs 2 workers: {title}",
            "",
            "| sweep | workers | wall [s] | run CPU [s] | steady runs/s | load before | load after |",
            "|---|---|---|---|---|---|---|",
        ]
        for tag, v in r.items():
            if isinstance(v, dict):
                lines.append(
                    f"| {tag} | {v['workers']} | {v['wall_s']} | {v['sum_run_cpu_s']} | "
                    f"{v.get('steady_runs_per_s')} | {v['load_before']} | {v['load_after']} |"
                )
        lines += [
            "",
            f"wall ratio (1 worker / 2 workers, ABBA sums): {r['ratio_1_over_2']}; steady throughput "
            f"ratio (2 / 1): {r.get('steady_throughput_ratio_2_over_1')}; results identical: "
            f"{r['results_identical_1_vs_2']}",
            "",
        ]
    for key in ("scheduler", "kill_worker", "kill_client"):
        if key in rep:
            lines += [f"## {key}", "", "```", json.dumps(rep[key], indent=1, default=str), "```", ""]
    Path(path).write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()

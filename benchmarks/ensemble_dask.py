"""Ensembles on Dask: scaling over worker processes, overhead against threads, 1M bodies to Zarr.

The Fig 9 asteroid under random impact sequences (RandomImpacts, one per year on average),
`splitting` step 1e-3, 21 samples per body. Three measurements (issue 14):

1. scaling: the same N = 100,000 run on a LocalCluster of 1 and of 2 worker processes (one
   thread each), each cluster started and warmed up (numba's cache loaded in every worker)
   before the timing; target 2 workers >= 1.8x one;
2. overhead: the 2-worker run against the in-process engine (simulate_ensemble, 2 threads) on
   the same run, end to end (results gathered into memory); target <= 10 %;
3. N = 1,000,000 bodies to a Zarr store through `run_ensemble_to_store` on a 2-worker
   LocalCluster, in a fresh process: peak RSS (VmHWM, see _maxrss_mb) of that process (driver, scheduler and the
   nannies, which a LocalCluster runs in it) plus its worker processes; target < 2 GB.

The results of 1. and 2. are also compared bit for bit (the same answer on every engine).
"""
from __future__ import annotations

import json
import os
from pathlib import Path
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
from common import Timer, section

from tumble_ros.core import IntegratorSettings, load_scenario, RandomImpacts, simulate_ensemble
from tumble_ros.core import kernels

CONFIG = Path(__file__).resolve().parents[1] / "tumble_ros" / "config" / "fig9.yaml"
SCALING_TARGET, OVERHEAD_TARGET, RSS_TARGET_GB = 1.8, 0.10, 2.0


def scenario(span: float):
    return load_scenario(CONFIG).replace(duration=span, output_interval=span / 20,
                                         integrator=IntegratorSettings(method="splitting", step=1e-3))


def inputs(n: int) -> dict:
    return {"impacts": RandomImpacts(rate=1.0, torque=1e6, seed=14), "n_bodies": n}


def _maxrss_mb() -> float:
    """
    Peak resident memory of this process [MB]: VmHWM, the high-water mark of its own memory.

    Not getrusage's ru_maxrss: Linux keeps that across execve (exec_mmap folds the old memory's
    high-water mark into it), so a process started by subprocess from a big parent (vfork, then
    exec) reports the parent's peak. The 1M run started from `make bench`'s process showed
    ~1 GB for a driver that peaks at ~0.4 GB on its own.
    """
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _pid_maxrss_mb() -> tuple[int, float]:
    return os.getpid(), _maxrss_mb()


def million(n: int, span: float, store: str) -> dict:
    """The 1M-bodies run, in this (fresh) process: what the section runs as a subprocess."""
    from tumble_ros.ensembles import dask_client, run_ensemble_to_store

    sc = scenario(span)
    start = time.perf_counter()
    with dask_client(workers=2) as client:
        summary = run_ensemble_to_store(sc, store, **inputs(n), client=client, overwrite=True)
        workers = client.run(_maxrss_mb)
        # a LocalCluster's nannies live in this process (counted as the driver) or apart
        nannies = {k: mb for k, (pid, mb) in client.run(_pid_maxrss_mb, nanny=True).items()
                   if pid != os.getpid()}
    wall = time.perf_counter() - start
    return {"n": n, "span": span, "wall_s": wall, "body_steps": summary.body_steps,
            "succeeded": summary.succeeded, "chunks": summary.n_chunks,
            "chunk_size": summary.chunk_size, "driver_mb": _maxrss_mb(),
            "workers_mb": sorted(workers.values()), "nannies_mb": sorted(nannies.values()),
            "store_mb": sum(f.stat().st_size for f in Path(store).rglob("*") if f.is_file()) / 2**20}


@section("Ensembles on Dask: scaling, overhead, 1M bodies to Zarr (issue 14)", order=21)
def dask_section(ctx):
    from tumble_ros.ensembles import dask_client, run_ensemble

    if not kernels.COMPILED:
        ctx.note("numba not available: skipped")
        return None
    n = 1_000 if ctx.quick else 100_000
    span = 0.5
    sc, kw = scenario(span), inputs(n)
    simulate_ensemble(sc.replace(duration=0.01, output_interval=0.01), n_bodies=2)  # compile/load
    with Timer() as tm:
        threads = simulate_ensemble(sc, **kw)
    steps = int(threads.n_steps.sum())
    rows = [["in-process threads (simulate_ensemble)", os.cpu_count(), "-", tm.seconds,
             steps / tm.seconds, "reference"]]
    times, results = {"threads": tm.seconds}, {}
    # quick: one 2-worker cluster only (each start-up costs seconds; no verdict is given anyway)
    for workers in ((2,) if ctx.quick else (1, 2)):
        with Timer() as up:
            cluster = dask_client(workers=workers)
            client = cluster.__enter__()
        try:
            run_ensemble(sc.replace(duration=0.01, output_interval=0.01), n_bodies=4 * workers,
                         client=client, chunk_size=1)   # every worker loads the compiled loop
            with Timer() as tm:
                r = run_ensemble(sc, **kw, client=client)
        finally:
            cluster.__exit__(None, None, None)
        same = all(np.array_equal(getattr(r, f), getattr(threads, f), equal_nan=True)
                   for f in ("omega", "euler", "quaternion", "jacobi", "n_steps"))
        times[workers] = tm.seconds
        rows.append([f"LocalCluster, {workers} worker process(es)", workers, up.seconds, tm.seconds,
                     steps / tm.seconds, "bit-identical" if same else "DIFFERENT"])
    ctx.table(["engine", "processes/threads", "cluster start-up [s]", f"N = {n:,} [s]",
               "body-steps/s", "results vs threads"], rows)
    if ctx.quick:
        ctx.note("quick: the 1-worker cluster (scaling) and the 1M-body run to Zarr are left out")
        return dict(threads_s=times["threads"], two_workers_s=times[2], body_steps=steps)
    scaling = times[1] / times[2]
    overhead = times[2] / times["threads"] - 1.0
    ctx.print(f"  body-steps per run: {steps:,} ({span:g} yr at step 1e-3, 21 samples per body)")
    ctx.print(f"  target scaling (2 workers >= {SCALING_TARGET}x 1 worker): "
              + ctx.verdict(scaling >= SCALING_TARGET, f"MISSED by {100 * (1 - scaling / SCALING_TARGET):.0f} %")
              + f": {scaling:.2f}x")
    ctx.print(f"  target overhead (2-worker LocalCluster vs 2 threads <= {100 * OVERHEAD_TARGET:.0f} %): "
              + ctx.verdict(overhead <= OVERHEAD_TARGET, f"MISSED by {100 * (overhead - OVERHEAD_TARGET):.0f} points")
              + f": {100 * overhead:+.1f} % (start-up of the cluster not included, shown apart)")
    results.update(threads_s=times["threads"], one_worker_s=times[1], two_workers_s=times[2],
                   scaling=scaling, overhead=overhead, body_steps=steps)

    big = 1_000_000
    big_span = 0.2
    with tempfile.TemporaryDirectory(prefix="tumble_bench_") as tmp:
        proc = subprocess.run([sys.executable, __file__, "--million", str(big), str(big_span),
                               str(Path(tmp) / "ens.zarr")], capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"1M run failed: {proc.stderr[-2000:]}")
        m = json.loads(proc.stdout.strip().splitlines()[-1])
    total_mb = m["driver_mb"] + sum(m["workers_mb"]) + sum(m["nannies_mb"])
    ctx.table(["N", "span [yr]", "chunks", "wall [s]", "body-steps/s", "peak RSS driver [MB]",
               "workers [MB]", "nannies [MB]", "total [MB]", "store on disk [MB]"],
              [[f"{big:,}", big_span, f"{m['chunks']} x {m['chunk_size']}", m["wall_s"],
                m["body_steps"] / m["wall_s"], m["driver_mb"],
                " + ".join(f"{v:.0f}" for v in m["workers_mb"]),
                " + ".join(f"{v:.0f}" for v in m["nannies_mb"]) or "in the driver", total_mb,
                m["store_mb"]]])
    ctx.print(f"  target (N = {big:,}, 21 samples, to Zarr, peak RSS < {RSS_TARGET_GB:g} GB): "
              + ctx.verdict(total_mb < RSS_TARGET_GB * 1024)
              + f": {total_mb / 1024:.2f} GB in all processes ({m['succeeded']:,} bodies succeeded; "
              "wall time includes cluster start-up and the store's creation)")
    results.update(million=m, million_total_mb=total_mb)
    return results


if __name__ == "__main__" and len(sys.argv) == 5 and sys.argv[1] == "--million":
    print(json.dumps(million(int(sys.argv[2]), float(sys.argv[3]), sys.argv[4])))

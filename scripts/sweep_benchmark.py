"""Throughput of gearfmu.sweep: the same grid serial, on a LocalCluster with 1 and with 2 workers.

Prints, per way of running: points per second (end to end: cluster start, FMU shipping, store
writes included), and per point the time inside fmi2DoStep (the FMU's own stepping), the rest of
the point on its worker (the Python master loop: setReal/getReal per communication step, the
measures) and the remainder per worker (Dask, store writes, start-up), all in ms.

    .venv/bin/python scripts/sweep_benchmark.py /tmp/sweep-fmus/KurokawaSpurLumped.fmu \\
        --speeds-rpm 1000:12000:250 --torques-nm 185,370
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from gearfmu.store import DONE, Grid
from gearfmu.sweep import parse_values, sweep


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("fmu", type=Path)
    parser.add_argument("--speeds-rpm", default="1000:12000:250")
    parser.add_argument("--torques-nm", default="185,370")
    args = parser.parse_args(argv)
    grid = Grid(tuple(parse_values(args.speeds_rpm)), tuple(parse_values(args.torques_nm)))
    print(f"{args.fmu.name}: {np.prod(grid.shape)} points + {len(grid.torques_nm)} references")
    print("| run | wall (s) | points/s | fmi2DoStep per point (ms) | master loop per point (ms) | "
          "Dask + store per point and worker (ms) |")
    print("|---|---|---|---|---|---|")
    for label, workers in (("serial", 0), ("LocalCluster, 1 worker", 1), ("LocalCluster, 2 workers", 2)):
        with tempfile.TemporaryDirectory() as tmp:
            started = time.perf_counter()
            ds = sweep(args.fmu, grid, Path(tmp) / "bench.zarr", serial=workers == 0, n_workers=workers or None,
                       progress=False)
            wall = time.perf_counter() - started
        done = ds["status"].values == DONE
        n = int(done.sum()) + len(grid.torques_nm)
        fmu_ms = 1e3 * np.nanmean(ds["fmu_s"].values[done])
        point_ms = 1e3 * np.nanmean(ds["wall_s"].values[done])
        rest_ms = 1e3 * wall * max(workers, 1) / n - point_ms
        print(f"| {label} | {wall:.1f} | {n / wall:.1f} | {fmu_ms:.1f} | {point_ms - fmu_ms:.1f} | {rest_ms:.1f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

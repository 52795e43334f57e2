"""Speed × torque × parameter sweeps of a gear-pair FMU on Dask distributed.

    python -m gearfmu.sweep FMU --speeds-rpm 100:6000:60 --torques-nm 100,200,370 \\
        --out sweep.zarr --png sweep.png [--param mesh_damping_ratio=0.05,0.15] [--scheduler tcp://HOST:8786]

Each grid point is one independent FMU run (operating_point.GearPairRunner): driven to its
dynamic steady state, then measured over whole mesh cycles. The points are cut into chunks; a
chunk is one Dask task, and runs on one FMU instance that is reset between points (fmpy's
parameter-variation example). The FMU's bytes travel to the workers once (``Client.scatter``);
a worker unpacks them into its own temporary directory.

Without ``--scheduler`` a ``LocalCluster`` with one single-threaded worker process per core runs
the chunks; with it, the same code runs on an existing cluster (``dask scheduler`` and
``dask worker tcp://HOST:8786`` on the machines; every worker needs this package installed).
``--serial`` runs the chunks in this process, without Dask (the reference the distributed runs
are compared with, bit for bit).

The client is the store's only writer: it writes each chunk's points as the chunk's result
arrives (store.Writer), so a killed worker loses at most its running chunk — Dask reschedules it —
and an interrupted client loses nothing already written. Run the same command again to finish a
sweep: points already in the store are skipped.
"""

from __future__ import annotations

import argparse
import hashlib
import math
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from . import store
from .operating_point import GearPairRunner, Recording
from .store import Grid

REFERENCE_MESH_FREQUENCY_HZ = 100.0   # the quasi-static reference point: far below any mesh mode here


# ---------------------------------------------------------------------------------------------
# Worker side
# ---------------------------------------------------------------------------------------------

_unpacked: dict[str, tuple[str, str]] = {}   # FMU sha256 → (fmu path, unzip dir), per process


def _local_fmu(fmu_bytes: bytes, sha256: str) -> tuple[str, str]:
    """Write and unpack the FMU once per worker process (one directory per process: workers on one
    machine never race on the same files)."""
    if sha256 not in _unpacked:
        from fmpy import extract

        directory = Path(tempfile.gettempdir()) / f"gearfmu-sweep-{sha256[:16]}-{os.getpid()}"
        directory.mkdir(parents=True, exist_ok=True)
        fmu_path = directory / "model.fmu"
        fmu_path.write_bytes(fmu_bytes)
        _unpacked[sha256] = (str(fmu_path), extract(str(fmu_path), unzipdir=str(directory / "unzipped")))
    return _unpacked[sha256]


def run_chunk(fmu_bytes: bytes, sha256: str, grid: Grid, tasks: list, recording: Recording) -> list:
    """Run a chunk of tasks on one FMU instance. A task is ("point", grid index) or
    ("reference", (torque index, *parameter indices)); returns [(kind, index, result), …]."""
    fmu_path, unzip_dir = _local_fmu(fmu_bytes, sha256)
    runner = GearPairRunner(fmu_path, unzip_dir, instance_name=f"sweep-{os.getpid()}")
    results = []
    try:
        for kind, index in tasks:
            if kind == "point":
                speed, torque, parameters = grid.point(index)
            else:
                _, torque, parameters = grid.point((None, *index))
                speed = REFERENCE_MESH_FREQUENCY_HZ * 60.0 / runner.pair.teeth_1
            results.append((kind, index, runner.run(speed, torque, parameters, recording)))
    finally:
        runner.close()
    return results


# ---------------------------------------------------------------------------------------------
# Client side
# ---------------------------------------------------------------------------------------------

def build_fmu(spec: Path, model: str = "lumped", out_dir: Path | None = None) -> Path:
    """A spec (.toml) → an .fmu, with the repository's fmu-build (on PATH or in target/release)."""
    tool = _fmu_build()
    out = Path(out_dir or tempfile.mkdtemp(prefix="gearfmu-build-")) / f"{Path(spec).stem}-{model}.fmu"
    out.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run([tool, "build", str(spec), "-o", str(out), "--model", model], check=True)
    return out


def operating_torque_nm(fmu: Path) -> float:
    """The torque on gear 1 (N·m) the FMU was built for: the spec's [operating] torque_nm or the
    pair's rated torque, from the tool's vendor annotation in modelDescription.xml (FMI 2.0 §2.2.6)."""
    import xml.etree.ElementTree as ET
    import zipfile

    with zipfile.ZipFile(fmu) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
    point = root.find("./VendorAnnotations/Tool[@name='gearfmu']/OperatingPoint")
    if point is None:
        raise ValueError(f"{fmu} has no gearfmu operating point (built by an older fmu-build): give --torques-nm")
    return float(point.attrib["torque_1"])


def _fmu_build() -> str:
    repo = Path(__file__).resolve().parents[2]
    return shutil.which("fmu-build") or str(repo / "target" / "release" / "fmu-build")


def linearized_mesh_frequencies(fmu: Path, grid: Grid) -> dict:
    """PMOR-Hertz: {reference index: its mesh mode linearized over a pitch (Hz)} from
    `fmu-build linearize` — the elastic gears' own linearized model, which the rigid two-inertia
    formula on the mean stiffness misses (their rims and webs move with the teeth). Only for
    grids that keep the inertias at their defaults; {} where fmu-build is not at hand."""
    tool = _fmu_build()
    if not Path(tool).exists() or {"inertia_1", "inertia_2"} & set(grid.parameters):
        return {}
    result = {}
    for index in np.ndindex(*grid.shape[1:]):
        _, torque, parameters = grid.point((None, *index))
        command = [tool, "linearize", str(fmu), "--torque-nm", repr(torque), "-n", "0", "--positions", "32"]
        if "mesh_damping_ratio" in parameters:
            command += ["--mesh-damping-ratio", repr(parameters["mesh_damping_ratio"])]
        out = subprocess.run(command, check=True, capture_output=True, text=True).stdout
        result[tuple(int(i) for i in index)] = float(out.strip().splitlines()[-1].split(":")[-1].split()[0])
    return result


def _chunks(tasks: list, chunk_size: int) -> list[list]:
    return [tasks[i:i + chunk_size] for i in range(0, len(tasks), chunk_size)]


def sweep(fmu: str | Path, grid: Grid, out: str | Path, *, client=None, scheduler: str | None = None,
          n_workers: int | None = None, serial: bool = False, recording: Recording = Recording(),
          chunk_size: int | None = None, retry_failed: bool = False, progress: bool = True,
          on_chunk=None, model: str = "lumped"):
    """Run every pending point of `grid` and write it into the Zarr store `out`; returns the store
    as an xarray Dataset. `fmu` may be a spec (.toml), built with `model` first.

    Execution: `serial`, or an existing `client`, or a cluster at `scheduler`, or a LocalCluster
    with `n_workers` single-threaded worker processes (default: one per core).
    `on_chunk(points_written)` is called after each chunk is written (progress hooks, tests).
    """
    fmu = Path(fmu)
    if fmu.suffix == ".toml":
        fmu = build_fmu(fmu, model)
    fmu_bytes = fmu.read_bytes()
    sha256 = hashlib.sha256(fmu_bytes).hexdigest()

    # The pair's facts (teeth, base radii, parameter defaults) from the FMU itself, on the client.
    fmu_path, unzip_dir = _local_fmu(fmu_bytes, sha256)
    probe = GearPairRunner(fmu_path, unzip_dir, instance_name="sweep-probe")
    pair = probe.pair
    probe.close()
    unknown = set(grid.parameters) - set(pair.start_values)
    if unknown:
        raise ValueError(f"not parameters of {fmu.name}: {sorted(unknown)} (it has {sorted(pair.start_values)})")

    out = Path(out)
    store.create(out, grid, pair, recording, fmu.name, sha256)
    points, references = store.pending(out, retry_failed)
    # References first: they are few, and the plots need them whatever else finishes.
    tasks = [("reference", index) for index in references] + [("point", index) for index in points]
    writer = store.Writer(out)
    if not pair.mesh_stiffness_is_whole_mesh:
        writer.write_linearized(linearized_mesh_frequencies(fmu, grid))

    def write(results: list) -> None:
        writer.write_references([(index, grid.point((None, *index))[2], result)
                                 for kind, index, result in results if kind == "reference"])
        writer.write_points([(index, result) for kind, index, result in results if kind == "point"])

    bar = None
    if progress and tasks:
        from tqdm import tqdm
        bar = tqdm(total=len(tasks), unit="point", desc=fmu.name)

    if serial:
        for chunk in _chunks(tasks, chunk_size or 8):
            write(run_chunk(fmu_bytes, sha256, grid, chunk, recording))
            if bar is not None:
                bar.update(len(chunk))
            if on_chunk:
                on_chunk(len(chunk))
    elif tasks:
        from dask.distributed import Client, LocalCluster, as_completed

        own_cluster = own_client = None
        if client is None:
            if scheduler:
                client = own_client = Client(scheduler)
            else:
                own_cluster = LocalCluster(n_workers=n_workers or os.cpu_count(), threads_per_worker=1,
                                           processes=True, dashboard_address=None)
                client = own_client = Client(own_cluster)
        try:
            workers = max(1, len(client.scheduler_info()["workers"]))
            # Several chunks per worker: the load balances, and a lost worker loses little.
            size = chunk_size or max(1, min(16, math.ceil(len(tasks) / (4 * workers))))
            fmu_future = client.scatter(fmu_bytes, broadcast=True)
            futures = [client.submit(run_chunk, fmu_future, sha256, grid, chunk, recording, pure=False)
                       for chunk in _chunks(tasks, size)]
            lost = 0
            for future, results in as_completed(futures, with_results=True, raise_errors=False):
                if future.status == "error":   # e.g. KilledWorker after repeated worker deaths
                    lost += 1
                    continue
                write(results)
                if bar is not None:
                    bar.update(len(results))
                if on_chunk:
                    on_chunk(len(results))
            if lost:
                print(f"sweep: {lost} chunk(s) failed on the cluster; their points stay pending — run again")
        finally:
            if own_client is not None:
                own_client.close()
            if own_cluster is not None:
                own_cluster.close()
    if bar is not None:
        bar.close()
    return store.load(out)


# ---------------------------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------------------------

def parse_values(text: str) -> list[float]:
    """"a,b,c" → [a, b, c]; "start:stop:step" → start, start+step, … up to stop inclusive."""
    if ":" in text:
        start, stop, step = (float(x) for x in text.split(":"))
        count = int(math.floor((stop - start) / step + 1e-9)) + 1
        return [start + k * step for k in range(count)]
    return [float(x) for x in text.split(",") if x]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m gearfmu.sweep", description=__doc__.split("\n")[0])
    parser.add_argument("fmu", type=Path, help="the .fmu, or a spec .toml (built with --model)")
    parser.add_argument("--speeds-rpm", required=True, help="gear-1 speeds: a,b,c or start:stop:step")
    parser.add_argument("--torques-nm", help="gear-1 driving torques: a,b,c or start:stop:step "
                        "(default: the operating torque the FMU was built for)")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUES",
                        help="sweep an FMU parameter too, e.g. mesh_damping_ratio=0.05,0.15 (repeatable)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="hold an FMU parameter at a value (a one-value --param)")
    parser.add_argument("--out", type=Path, required=True, help="the Zarr store (resumed if it exists)")
    parser.add_argument("--png", type=Path, help="plot the store (and the --overlay stores)")
    parser.add_argument("--overlay", type=Path, action="append", default=[], help="another store on the same plot")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tcp://HOST:8786")
    parser.add_argument("--workers", type=int, help="LocalCluster worker processes (default: one per core)")
    parser.add_argument("--serial", action="store_true", help="run in this process, without Dask")
    parser.add_argument("--chunk-size", type=int, help="points per task (default: ~4 tasks per worker, ≤ 16)")
    parser.add_argument("--retry-failed", action="store_true", help="run failed points again")
    parser.add_argument("--model", default="lumped", help="model kind when FMU is a spec")
    parser.add_argument("--samples-per-mesh-period", type=int, default=Recording.samples_per_mesh_period)
    parser.add_argument("--cycles-per-window", type=int, default=Recording.cycles_per_window)
    parser.add_argument("--settle-s", type=float, default=Recording.settle_s)
    parser.add_argument("--max-record-s", type=float, default=Recording.max_record_s)
    args = parser.parse_args(argv)

    parameters = {}
    for item in args.param + args.set:
        name, values = item.split("=", 1)
        parameters[name] = parse_values(values)
    if args.torques_nm is None:
        fmu = args.fmu
        if fmu.suffix == ".toml":
            fmu = build_fmu(fmu, args.model)
            args.fmu = fmu
        torques = (operating_torque_nm(fmu),)
        print(f"torque: the FMU's operating torque, {torques[0]:.6g} N·m (--torques-nm to choose)")
    else:
        torques = tuple(parse_values(args.torques_nm))
    grid = Grid(tuple(parse_values(args.speeds_rpm)), torques, parameters)
    recording = Recording(samples_per_mesh_period=args.samples_per_mesh_period,
                          cycles_per_window=args.cycles_per_window, settle_s=args.settle_s,
                          max_record_s=args.max_record_s)
    started = time.perf_counter()
    ds = sweep(args.fmu, grid, args.out, scheduler=args.scheduler, n_workers=args.workers, serial=args.serial,
               recording=recording, chunk_size=args.chunk_size, retry_failed=args.retry_failed, model=args.model)
    wall = time.perf_counter() - started
    status = ds["status"].values
    print(f"{args.out}: {status.size} points, {np.sum(status == store.DONE)} done, "
          f"{np.sum(status == store.FAILED)} failed, {np.sum(status == store.PENDING)} pending; {wall:.1f} s")
    for index in np.argwhere(status == store.FAILED)[:3]:
        print("  failed:", dict(zip(ds["status"].dims, (float(ds[d].values[i]) for d, i in zip(ds["status"].dims, index)))),
              str(ds["error"].values[tuple(index)])[:300])
    if args.png:
        from .plots import plot_sweeps
        plot_sweeps([args.out, *args.overlay], args.png)
        print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    # Run main() from the imported module, not from __main__: the functions Dask ships to the
    # workers must then be pickled by reference to gearfmu.sweep, which the workers import.
    from gearfmu.sweep import main as _main

    raise SystemExit(_main())

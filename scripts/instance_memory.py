#!/usr/bin/env python3
"""Resident memory that each instance of an FMU adds in one process (fmpy), after instantiation and
initialization: instances of one FMU share its model data (src/fmu/shared_model.rs), so the
first instance carries the model and every further one only its state.

    .venv/bin/python scripts/instance_memory.py out/KurokawaSpur.fmu [--instances 4]
"""
import argparse
import shutil

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave


def rss_kib() -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise RuntimeError("no VmRSS")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("fmu")
    parser.add_argument("--instances", type=int, default=4)
    args = parser.parse_args()
    md = read_model_description(args.fmu)
    unzipdir = extract(args.fmu)
    slaves = []
    try:
        # The shared library loaded and one instance created and freed first, so the figures below
        # are the instances' own memory, not the library's code and the allocator's first arenas.
        warm = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier,
                         instanceName="warm-up")
        warm.instantiate()
        warm.freeInstance()
        before = rss_kib()
        start = before
        print(f"{args.fmu}: resident memory added per instance (instantiated and initialized)")
        for k in range(args.instances):
            slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier,
                              instanceName=f"i{k}")
            slave.instantiate()
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
            slave.exitInitializationMode()
            slaves.append(slave)
            now = rss_kib()
            print(f"  instance {k + 1}: +{(now - before) / 1024:.2f} MiB")
            before = now
        print(f"  {args.instances} instances: +{(before - start) / 1024:.2f} MiB in all")
    finally:
        for slave in slaves:
            slave.terminate()
            slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)


if __name__ == "__main__":
    main()

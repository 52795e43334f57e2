#!/usr/bin/env bash
# Builds the example FMU of the default pair (Kurokawa spur) with the PMOR-Hertz model — the FE
# gears reduced offline on a 10/10/10 mesh, ~45 s — and runs the 1-D drivetrain demo with it: motor → shaft →
# gear-pair FMU → shaft → load, co-simulated with fmpy (out/drivetrain.png), and as an SSP system of
# FMUs in libcosim and fmpy (out/drivetrain.ssp). Then example 3 of
# the paper with the PMOR-Hertz and the lumped FMU side by side (out/example3_dte.png).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo build --release --workspace
mkdir -p out
# Both FMUs from one build: the lumped FMU's mesh law is tabulated from the PMOR-Hertz build's statics.
./target/release/fmu-build build examples/kurokawa_spur.toml -o out/KurokawaSpur.fmu --lumped-fmu out/KurokawaSpurLumped.fmu
.venv/bin/python examples/drivetrain.py --fmu out/KurokawaSpur.fmu --png out/drivetrain.png
# The same drivetrain as an SSP system of FMUs (motor, shafts, load built by fmu-build element),
# run in libcosim and in fmpy against drivetrain.py's element co-simulation.
./target/release/fmu-build ssp --gear-fmu out/KurokawaSpur.fmu -o out/drivetrain.ssp
.venv/bin/python examples/drivetrain_ssp.py out/drivetrain.ssp --png out/drivetrain_ssp.png
.venv/bin/python scripts/example3.py out/KurokawaSpur.fmu out/KurokawaSpurLumped.fmu --png out/example3_dte.png

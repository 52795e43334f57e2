#!/usr/bin/env bash
# Builds the example FMU (Kurokawa spur pair, lumped model) and runs the 1-D drivetrain demo:
# motor → shaft → gear-pair FMU → shaft → load, co-simulated with fmpy. Writes out/drivetrain.png.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo build --release --workspace
mkdir -p out
./target/release/fmu-build build examples/kurokawa_spur.toml -o out/KurokawaSpur.fmu --model lumped
.venv/bin/python examples/drivetrain.py --fmu out/KurokawaSpur.fmu --png out/drivetrain.png

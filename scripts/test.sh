#!/usr/bin/env bash
# Every test: Rust (unit, integration, FMI C API, physics) and Python (fmpy drives the .fmu).
set -euo pipefail
cd "$(dirname "$0")/.."
# One FE reduction per distinct model for the whole run, shared by the Rust tests, fmu-build and
# the Python tests (src/rom/build_cache.rs; keyed by the code, the pair, the mesh and the options).
export GEARFMU_BUILD_CACHE="${GEARFMU_BUILD_CACHE:-$PWD/target/build-cache}"
stage() { echo "test.sh: $1 done at ${SECONDS} s"; }
bash scripts/setup.sh
stage "set-up"
# No import circle between source files (issue 41): fails naming the circle.
.venv/bin/python scripts/import_circles.py
# The workspace build produces the FMU binary (target/release/libgearfmu.so) that fmu-build packs.
cargo build --release --workspace --all-targets
stage "build"
cargo test --release --workspace
stage "Rust tests"
.venv/bin/python -m pytest tests/python -q --durations=25
stage "Python tests"

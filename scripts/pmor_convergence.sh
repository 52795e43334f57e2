#!/usr/bin/env bash
# Convergence of the PMOR-Hertz FMU on example 3 (BENCHMARKS.md): DTE mean and peak-to-peak over
# the last mesh cycle and ω₂ at 25 ms, against the eigenmodes kept (n_k), the angular samples
# (n_θ), the shapes per sample (n_t: the load-sharing shapes; ROM torque), the mesh and the internal step; each row is one build + one fmpy run of scripts/example3.py.
# The DTE is sampled at a 20 µs communication step: at 0.1 ms the 3.8 kHz ringing of the mesh
# mode is caught at 2.6 points per period and the peak-to-peak depends on the sampling phase.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/convergence}
mkdir -p "$out"
spec=examples/kurokawa_spur.toml
only=${ROWS:-.}  # ROWS=regex runs only the rows whose name matches
row() {  # name, build options…, then "--" and example3 options
  local name=$1; shift
  [[ "$name" =~ $only ]] || return 0
  local build=() run=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do build+=("$1"); shift; done
  [ $# -gt 0 ] && shift
  run=("$@")
  local start=$(date +%s.%N)
  ./target/release/fmu-build build "$spec" -o "$out/$name.fmu" "${build[@]}" > "$out/$name.build.txt"
  local built=$(date +%s.%N)
  local line
  line=$(.venv/bin/python scripts/example3.py "$out/$name.fmu" --comm-step 2e-5 "${run[@]}" | grep "^| $name.fmu")
  printf '| %s | %.1f %s\n' "$name" "$(echo "$built - $start" | bc)" "${line#| $name.fmu }"
}
echo "| setting | offline build (s) | wall (s) | real-time factor | µs per doStep | memory (MiB) | ω₂ end (rad/s) | DTE mean (µm) | DTE RMS (µm) | DTE p-p (µm) |"
echo "|---|---|---|---|---|---|---|---|---|---|"
row default
row modes10 --modes 10
row modes40 --modes 40
row angles10 --angles 10
row angles40 --angles 40
row angles80 --angles 80
row linear --interpolation linear
row torque185 --rom-torques-nm 185
row sharing0 --sharing-shapes 0
row sharing0_torque185 --sharing-shapes 0 --rom-torques-nm 185
row fine_mesh --across 6 --profile 12 --rim 6
row mesh_4_8_4 --across 4 --profile 8 --rim 4
row mesh_8_8_8 --across 8 --profile 8 --rim 8
row mesh_10_8_10 --across 10 --profile 8 --rim 10
row mesh_8_16_8 --across 8 --profile 16 --rim 8
row mesh_10_20_10 --across 10 --profile 20 --rim 10
row mesh_12_24_12 --across 12 --profile 24 --rim 12

row step4us -- --max-step 4e-6
row step1us -- --max-step 1e-6
row modes80 --modes 80

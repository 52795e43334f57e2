#!/usr/bin/env bash
# Installs what gearfmu needs on a fresh Debian machine (idempotent):
#  - libclang-dev: fmi-sys runs bindgen on the official FMI 2.0 headers at build time;
#  - a C compiler for fmi-sys's logger shim;
#  - .venv: a Python venv with fmpy, numpy, scipy, matplotlib, pytest, and for the sweeps dask[distributed],
#    xarray, zarr, tqdm (requirements.txt), plus this repository's Python package gearfmu (python/, editable).
set -euo pipefail
cd "$(dirname "$0")/.."

missing=()
dpkg -s libclang-dev >/dev/null 2>&1 || missing+=(libclang-dev)
command -v cc >/dev/null 2>&1 || missing+=(gcc)
python3 -c 'import venv, ensurepip' >/dev/null 2>&1 || missing+=(python3-venv)
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" = 0 ] || sudo="sudo"
  echo "setup: installing ${missing[*]} (apt)"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi

# An existing venv missing any of these (made before the sweeps) is completed, not recreated.
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c \
    'import fmpy, numpy, scipy, matplotlib, pytest, dask.distributed, xarray, zarr, tqdm, libcosimpy, gearfmu.sweep' >/dev/null 2>&1; then
  echo "setup: creating/completing .venv (requirements.txt, python/ as the gearfmu package)"
  [ -x .venv/bin/python ] || python3 -m venv .venv
  .venv/bin/pip install -q --disable-pip-version-check -r requirements.txt
  .venv/bin/pip install -q --disable-pip-version-check --no-deps -e python/
fi

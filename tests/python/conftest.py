"""Shared fixtures for the Python-side tests of the gearfmu FMUs.

* ``gear_fmus`` (session): builds KurokawaSpur.fmu and KurokawaHelical.fmu with
  ``target/release/fmu-build build ...`` (after one `cargo build --release --workspace --all-targets`) and dumps the mesh law of
  each spec with ``fmu-build inspect --json`` into a temporary directory.
* ``gear_case``: the same, parametrized over both gear pairs.
* ``make_slave``: opens ``fmpy.fmi2.FMU2Slave`` instances (freed at teardown).
* ``log_capture``: an fmi2 logger that records every message the FMUs emit.
* ``drivetrain``: the ``examples/drivetrain.py`` module.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import importlib.util
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]

# name used in the tests -> (spec, FMU file under target/fmu, fmu-build model kind).
# The lumped FMUs carry the mesh-law tests; every FMI-level test (validation, FMU state, bad
# inputs, the second client) also runs against the PMOR-Hertz FMU of the spur pair.
GEAR_SPECS = {
    "spur": ("examples/kurokawa_spur.toml", "KurokawaSpur.fmu", "lumped"),
    "helical": ("examples/kurokawa_helical.toml", "KurokawaHelical.fmu", "lumped"),
}
PMOR_SPECS = {
    "spur-pmor": ("examples/kurokawa_spur.toml", "KurokawaSpurPmor.fmu", "pmor-hertz"),
    # Issue 40: the helical pair builds in under a minute; its quasi-static DTE is checked
    # against `fmu-build ste` (test_master_coupling). Its build writes the lumped helical FMU.
    "helical-pmor": ("examples/kurokawa_helical.toml", "KurokawaHelicalPmor.fmu", "pmor-hertz"),
}
# The FMUs every FMI-behaviour test runs on: both lumped ones and the spur PMOR-Hertz one (the
# helical PMOR-Hertz FMU shares its FMI layer and model code; it is checked on its physics).
FMI_CASES = sorted(GEAR_SPECS) + ["spur-pmor"]

REAL_OUTPUTS = ("phi_1", "phi_2", "w_1", "w_2", "dte", "dte_angle", "mesh_force", "mesh_stiffness")


_WORKSPACE_BUILT = False


def build_workspace() -> None:
    """`cargo build --release --workspace --all-targets`, once per session.

    The same targets as scripts/test.sh's build, so nothing recompiles: a build of fewer targets
    (`cargo run -p fmu-build`, `cargo build --workspace`) resolves the dev-dependencies' features
    differently and rebuilds the library, the FMU binary and fmu-build each time it alternates
    with one of more (a minute to three per switch, measured in CI). It makes the FMU binary
    (target/release/libgearfmu.so) that fmu-build packs, fmu-build and the Rust examples."""
    global _WORKSPACE_BUILT
    if _WORKSPACE_BUILT:
        return
    cargo = shutil.which("cargo")
    if cargo is None:
        pytest.fail("cargo is not on PATH; cannot build the FMUs")
    build = [cargo, "build", "--release", "-q", "--workspace", "--all-targets"]
    proc = subprocess.run(build, cwd=REPO_ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.fail(f"`{' '.join(build)}` failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    _WORKSPACE_BUILT = True


# Options whose value is a file fmu-build writes: the cache stores those files.
OUTPUT_OPTIONS = ("-o", "--output", "--lumped-fmu", "--json", "--csv", "--png", "--vtk")
CACHE_DIR = REPO_ROOT / "target" / "fmu-cache"
# The library's build cache (src/rom/build_cache.rs): a model the Rust tests built is not reduced
# again by the fmu-build calls here (scripts/test.sh sets it for both; pytest alone sets it too).
os.environ.setdefault("GEARFMU_BUILD_CACHE", str(REPO_ROOT / "target" / "build-cache"))


@functools.lru_cache(maxsize=None)
def _tool_identity() -> str:
    """The fmu-build binary and the FMU binary it packs, hashed: a cache entry made by other
    code is never taken (any change to the library changes both)."""
    digest = hashlib.sha256()
    for binary in ("fmu-build", "libgearfmu.so"):
        digest.update((REPO_ROOT / "target" / "release" / binary).read_bytes())
    return digest.hexdigest()


def _repo_path(arg: str) -> Path:
    path = Path(arg)
    return path if path.is_absolute() else REPO_ROOT / path


def _fmu_build(*args: str) -> subprocess.CompletedProcess:
    """`target/release/fmu-build args…`, run once per distinct call (issue 41: one build per
    distinct model for the session, and across sessions while the code is unchanged).

    The key: the two binaries (`_tool_identity`), the arguments with each output file named by
    its position only and each input file (the spec, a gear FMU handed to `ssp` or `linearize`)
    by its bytes. A hit copies the stored outputs to the paths asked and
    returns the stored stdout/stderr. GEARFMU_FMU_CACHE=off runs every call."""
    build_workspace()
    cmd = [str(REPO_ROOT / "target" / "release" / "fmu-build"), *args]
    key, outputs = hashlib.sha256(_tool_identity().encode()), []
    for i, arg in enumerate(args):
        if i > 0 and args[i - 1] in OUTPUT_OPTIONS:
            key.update(f"\0<output {len(outputs)}>".encode())
            outputs.append(_repo_path(arg))
            continue
        # An input file by its bytes, not its name: a spec written to a temporary folder, or
        # named relative or absolute, is the same model.
        path = _repo_path(arg)
        key.update(b"\0<file>" + path.read_bytes() if path.is_file() else b"\0" + arg.encode())
    entry = CACHE_DIR / key.hexdigest()[:32]
    use_cache = os.environ.get("GEARFMU_FMU_CACHE", "on") != "off"
    if use_cache and entry.is_dir():
        for i, out in enumerate(outputs):
            out.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(entry / f"output{i}", out)
        return subprocess.CompletedProcess(cmd, 0, (entry / "stdout.txt").read_text(), (entry / "stderr.txt").read_text())
    proc = subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.fail(f"`{' '.join(cmd)}` failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    if use_cache and all(out.is_file() for out in outputs):
        # Written beside, then renamed: an entry is whole or absent.
        CACHE_DIR.mkdir(parents=True, exist_ok=True)
        partial = Path(tempfile.mkdtemp(dir=CACHE_DIR, prefix="partial-"))
        for i, out in enumerate(outputs):
            shutil.copyfile(out, partial / f"output{i}")
        (partial / "stderr.txt").write_text(proc.stderr)
        (partial / "stdout.txt").write_text(proc.stdout)
        try:
            partial.rename(entry)
        except OSError:  # another session stored the same entry first
            shutil.rmtree(partial, ignore_errors=True)
    return proc


@dataclass(frozen=True)
class GearCase:
    name: str              # "spur" / "helical"
    spec_path: Path        # examples/kurokawa_*.toml
    fmu_path: Path         # target/fmu/Kurokawa*.fmu
    mesh_json_path: Path   # fmu-build inspect --json dump
    mesh: dict             # the parsed dump
    unzip_dir: Path        # one shared extraction: all instances load the same .so
    kind: str = "lumped"   # the fmu-build model kind: "lumped" or "pmor-hertz"


@pytest.fixture(scope="session")
def gear_fmus(tmp_path_factory) -> dict[str, GearCase]:
    from fmpy import extract

    out_dir = tmp_path_factory.mktemp("gearfmu")
    fmu_dir = REPO_ROOT / "target" / "fmu"
    fmu_dir.mkdir(parents=True, exist_ok=True)
    # A PMOR-Hertz build writes the lumped FMU of the same spec beside it (`--lumped-fmu`: the
    # law from the build's own statics, equal to a separate `--model lumped` reduction by
    # `pmor_dynamics::the_builds_lumped_mesh_law_is_the_one_a_separate_reduction_gives`): one
    # reduction per spec, not two.
    built = set()
    for spec, fmu_file, kind in PMOR_SPECS.values():
        args = ["build", spec, "-o", str(fmu_dir / fmu_file), "--model", kind]
        for lumped_spec, lumped_file, _ in GEAR_SPECS.values():
            if lumped_spec == spec:
                args += ["--lumped-fmu", str(fmu_dir / lumped_file)]
                built.add(lumped_file)
        _fmu_build(*args)
        built.add(fmu_file)
    cases = {}
    for name, (spec, fmu_file, kind) in {**GEAR_SPECS, **PMOR_SPECS}.items():
        fmu_path = fmu_dir / fmu_file
        if fmu_file not in built:
            _fmu_build("build", spec, "-o", str(fmu_path.relative_to(REPO_ROOT)), "--model", kind)
    for name, (spec, fmu_file, kind) in {**GEAR_SPECS, **PMOR_SPECS}.items():
        fmu_path = fmu_dir / fmu_file
        # The law the spec's lumped FMU carries (`inspect --from-fmu`: the FE-fed law of the build's
        # own statics, what that FMU runs), not a second reduction of the same spec.
        lumped_fmu = next(fmu_dir / f for s, f, _ in GEAR_SPECS.values() if s == spec)
        mesh_json_path = out_dir / f"{name}_mesh.json"
        _fmu_build("inspect", spec, "--json", str(mesh_json_path), "--from-fmu", str(lumped_fmu))
        mesh = json.loads(mesh_json_path.read_text())
        unzip_dir = Path(extract(str(fmu_path), unzipdir=out_dir / f"{name}_unzipped"))
        cases[name] = GearCase(name, REPO_ROOT / spec, fmu_path, mesh_json_path, mesh, unzip_dir, kind)
    yield cases


RELIEVED_SPEC = "examples/kurokawa_spur_relieved.toml"


@pytest.fixture(scope="session")
def relieved_fmus(tmp_path_factory) -> dict[str, GearCase]:
    """The spur pair with tip relief and lead crowning (issue 27), both models from one build:
    ``relieved-pmor`` (PMOR-Hertz) and ``relieved`` (lumped, its mesh law from the same
    statics, written beside it with ``--lumped-fmu``)."""
    from fmpy import extract

    out_dir = tmp_path_factory.mktemp("relieved")
    paths = {"relieved-pmor": ("KurokawaSpurRelievedPmor.fmu", "pmor-hertz"),
             "relieved": ("KurokawaSpurRelieved.fmu", "lumped")}
    fmu = {name: REPO_ROOT / "target" / "fmu" / file for name, (file, _) in paths.items()}
    fmu["relieved"].parent.mkdir(parents=True, exist_ok=True)
    _fmu_build("build", RELIEVED_SPEC, "-o", str(fmu["relieved-pmor"]), "--model", "pmor-hertz",
               "--lumped-fmu", str(fmu["relieved"]))
    cases = {}
    for name, (_, kind) in paths.items():
        unzip_dir = Path(extract(str(fmu[name]), unzipdir=out_dir / f"{name}_unzipped"))
        cases[name] = GearCase(name, REPO_ROOT / RELIEVED_SPEC, fmu[name], Path(), {}, unzip_dir, kind)
    yield cases


@pytest.fixture(params=sorted(GEAR_SPECS))
def gear_case(request, gear_fmus) -> GearCase:
    """The lumped FMUs (their mesh law is what the mesh-dump tests check)."""
    return gear_fmus[request.param]


@pytest.fixture(params=FMI_CASES)
def fmi_case(request, gear_fmus) -> GearCase:
    """Every FMU kind, for the tests of FMI behaviour that must hold whatever the model."""
    return gear_fmus[request.param]


@pytest.fixture(scope="session")
def drivetrain():
    """examples/drivetrain.py, imported as a module."""
    path = REPO_ROOT / "examples" / "drivetrain.py"
    spec = importlib.util.spec_from_file_location("drivetrain", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["drivetrain"] = module
    spec.loader.exec_module(module)
    return module


# ---------------------------------------------------------------------------
# Logging
# ---------------------------------------------------------------------------


class LogCapture:
    """An fmi2CallbackFunctions whose logger records (instance, status, category, message).

    The FMU calls the logger with a printf format ("%s") and the text as a
    variadic argument, which ctypes cannot receive.  fmpy's native
    ``addLoggerProxy`` swaps in a C function that runs ``vsnprintf`` and then
    calls the Python logger with the formatted text.  The proxy keeps the
    Python logger in ONE process-wide static, so after this every fmpy proxy
    (including fmpy's default callbacks) reports here; this object must
    therefore live as long as the process (see ``_LOG_CAPTURE``) and records
    are told apart by instance name.
    """

    def __init__(self):
        from fmpy import calloc, free
        from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
        from fmpy.logging import addLoggerProxy

        self.records: list[tuple[str, int, str, str]] = []
        self._python_logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = self._python_logger
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(ctypes.byref(self.callbacks))

    def _log(self, env, instance_name, status, category, message):
        decode = lambda b: b.decode("utf-8", "replace") if b is not None else ""
        self.records.append((decode(instance_name), int(status), decode(category), decode(message)))

    def for_instance(self, instance_name: str) -> list[tuple[int, str, str]]:
        return [(s, c, m) for (i, s, c, m) in self.records if i == instance_name]


_LOG_CAPTURE: LogCapture | None = None


@pytest.fixture(scope="session")
def log_capture() -> LogCapture:
    global _LOG_CAPTURE
    if _LOG_CAPTURE is None:
        _LOG_CAPTURE = LogCapture()
    return _LOG_CAPTURE


# ---------------------------------------------------------------------------
# FMU instances
# ---------------------------------------------------------------------------


class GearSlave:
    """A thin wrapper over fmpy's FMU2Slave for one gear-pair instance."""

    def __init__(self, case: GearCase, instance_name: str, callbacks=None, logging_on=False,
                 parameters: dict | None = None, start_time: float = 0.0,
                 booleans: dict | None = None, inputs: tuple[float, float] | None = None):
        """``parameters``/``booleans``: start values set in initialization mode; ``inputs``:
        (τ₁, τ₂) set there too, so ``start_at_equilibrium`` solves the statics under them."""
        from fmpy import read_model_description
        from fmpy.fmi2 import FMU2Slave

        model = read_model_description(str(case.fmu_path))
        self.vr = {v.name: v.valueReference for v in model.modelVariables}
        self.instance_name = instance_name
        self.fmu = FMU2Slave(guid=model.guid, unzipDirectory=str(case.unzip_dir),
                             modelIdentifier=model.coSimulation.modelIdentifier,
                             instanceName=instance_name)
        self.fmu.instantiate(callbacks=callbacks, loggingOn=logging_on)
        self._freed = False
        self.fmu.setupExperiment(startTime=start_time)
        self.fmu.enterInitializationMode()
        for name, value in (parameters or {}).items():
            self.fmu.setReal([self.vr[name]], [float(value)])
        for name, value in (booleans or {}).items():
            self.fmu.setBoolean([self.vr[name]], [bool(value)])
        if inputs is not None:
            self.set_inputs(*inputs)
        self.fmu.exitInitializationMode()
        self._real_refs = [self.vr[n] for n in REAL_OUTPUTS]

    def set_inputs(self, tau_1: float, tau_2: float) -> None:
        self.fmu.setReal([self.vr["tau_1"], self.vr["tau_2"]], [tau_1, tau_2])

    def step(self, t: float, h: float) -> None:
        # noSetFMUStatePriorToCurrentPoint = False: the tests do roll back.
        self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h,
                        noSetFMUStatePriorToCurrentPoint=False)

    def outputs(self) -> tuple:
        """All real outputs plus contact_pairs, exactly as the FMU returns them."""
        return tuple(self.fmu.getReal(self._real_refs)) + tuple(self.fmu.getInteger([self.vr["contact_pairs"]]))

    def free(self) -> None:
        if not self._freed:
            self._freed = True
            self.fmu.freeInstance()


@pytest.fixture
def make_slave():
    """Factory: make_slave(case, name, **kw) -> GearSlave; all are freed at teardown."""
    slaves = []

    def factory(case: GearCase, instance_name: str, **kwargs) -> GearSlave:
        slave = GearSlave(case, instance_name, **kwargs)
        slaves.append(slave)
        return slave

    yield factory
    for slave in reversed(slaves):
        slave.free()


def drive_schedule(n_steps: int, seed: float = 0.0, t0: float = 0.0):
    """A deterministic, non-trivial input schedule with varying step sizes:
    yields (t, h, tau_1, tau_2) for n_steps communication steps starting at t0."""
    steps = (1e-4, 3e-5, 2e-4, 7e-5)
    t = t0
    for n in range(n_steps):
        h = steps[n % len(steps)]
        tau_1 = 120.0 + 40.0 * math.sin(0.37 * n + seed)
        tau_2 = -150.0 + 25.0 * math.cos(0.21 * n + 2.0 * seed)
        yield t, h, tau_1, tau_2
        t += h


@pytest.fixture(scope="session")
def schedule():
    return drive_schedule

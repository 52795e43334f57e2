"""The sweep's results on disk: one Zarr store, laid out as an xarray Dataset over the grid.

Dimensions: ``speed_rpm`` × ``torque_nm`` × one dimension per swept FMU parameter (named after
it), and ``mesh_order`` (1, 2, 3) for the DTE's mesh-order amplitudes. Every variable is chunked
one grid point per chunk, so writing a point touches only that point's chunk files; Zarr's local
store writes each file atomically (temporary file, then rename).

"Already done" is a property of the store: ``status`` is written *last* for each point (PENDING →
DONE or FAILED). A client killed in the middle of a point's writes leaves it PENDING, and the next
run computes it again and overwrites it. A failed point keeps the error text in ``error``.

Besides the grid points, each torque × parameter combination has one *reference* point: the same
drive at a low mesh frequency (quasi-static), whose mean mesh stiffness gives the linearized mesh
natural frequency (``mesh_natural_frequency_hz``) the resonance curves are read against.

Only the client writes (one writer); workers return results. The store uses the Zarr v2 format:
its fixed-width text type (the error messages) is specified there, not yet in v3.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr
import zarr

from .operating_point import MESH_ORDERS, PairFacts, Recording, mesh_natural_frequency_hz

PENDING, DONE, FAILED = 0, 1, 2
ERROR_CHARS = 1024

# Scalars measured at each grid point (see operating_point.GearPairRunner.run), name → unit/meaning.
POINT_MEASURES = {
    "dte_mean_m": "mean DTE over the window (m)",
    "dte_rms_m": "RMS of the DTE about its mean (m)",
    "dte_pp_m": "peak-to-peak DTE (m)",
    "mesh_force_mean_n": "mean mesh force (N)",
    "mesh_force_max_n": "maximum mesh force (N)",
    "static_mesh_force_n": "T1 / r_b1 (N)",
    "dynamic_factor": "K_v = maximum / static mesh force",
    "mesh_stiffness_mean_n_per_m": "mean of the FMU's mesh_stiffness output (N/m)",
    "contact_loss_share": "share of samples with contact_pairs = 0",
    "back_flank_share": "share of samples with mesh_force < 0 (coast flank)",
    "speed_1_mean_rpm": "mean speed of gear 1 (rpm)",
    "mesh_frequency_hz": "f_m = z1 n1 / 60 (Hz)",
    "load_damping_nms": "viscous load on gear 2 (N m s/rad)",
    "communication_step_s": "communication step (s)",
    "simulated_s": "simulated time, transient included (s)",
    "windows": "windows of whole mesh cycles run",
    "settled": "1 when the last two windows agreed to the tolerance",
    "steady_change": "relative change between the last two windows",
    "fmu_s": "wall time inside fmi2DoStep (s)",
    "wall_s": "wall time of the point on its worker (s)",
}
ORDER_MEASURE = "dte_order_amplitude_m"
REFERENCE_MEASURES = {
    "reference_mesh_stiffness_n_per_m": ("mesh_stiffness_mean_n_per_m", "mean mesh stiffness, quasi-static (N/m)"),
    "reference_dte_mean_m": ("dte_mean_m", "mean DTE, quasi-static (m)"),
    "reference_mesh_frequency_hz": ("mesh_frequency_hz", "mesh frequency of the reference point (Hz)"),
}
# Measures that depend on the machine, not on the model: excluded from result comparisons.
TIMINGS = ("fmu_s", "wall_s")


@dataclass(frozen=True)
class Grid:
    """Gear-1 speeds × gear-1 torques × any FMU parameters (name → values)."""

    speeds_rpm: tuple
    torques_nm: tuple
    parameters: dict = field(default_factory=dict)

    @property
    def dims(self) -> tuple:
        return ("speed_rpm", "torque_nm", *self.parameters)

    @property
    def shape(self) -> tuple:
        return (len(self.speeds_rpm), len(self.torques_nm), *(len(v) for v in self.parameters.values()))

    def coords(self) -> dict:
        return {"speed_rpm": np.asarray(self.speeds_rpm, float), "torque_nm": np.asarray(self.torques_nm, float),
                **{name: np.asarray(values, float) for name, values in self.parameters.items()}}

    def point(self, index: tuple) -> tuple[float, float, dict]:
        """(speed, torque, parameters) of a grid index (speed index may be None: the reference point)."""
        i_speed, i_torque, *i_params = index
        speed = None if i_speed is None else float(self.speeds_rpm[i_speed])
        params = {name: float(values[i]) for (name, values), i in zip(self.parameters.items(), i_params)}
        return speed, float(self.torques_nm[i_torque]), params


def create(path: Path, grid: Grid, pair: PairFacts, recording: Recording, fmu_name: str, fmu_sha256: str) -> None:
    """Lay out an empty store (every point PENDING); refuse to reuse a store of another FMU or grid."""
    path = Path(path)
    if path.exists():
        attrs = zarr.open_group(str(path), mode="r").attrs
        theirs = xr.open_zarr(str(path), consolidated=False, chunks=None)
        same_grid = all(name in theirs.coords and np.array_equal(theirs[name].values, values)
                        for name, values in grid.coords().items()) and tuple(theirs["status"].dims) == grid.dims
        if attrs.get("fmu_sha256") != fmu_sha256 or not same_grid or attrs.get("recording") != json.dumps(recording.as_attrs()):
            raise ValueError(f"{path} holds a sweep of another FMU, grid or recording; choose another --out")
        return
    dims, shape = grid.dims, grid.shape
    chunks = (1,) * len(dims)
    ref_dims, ref_shape = dims[1:], shape[1:]
    data = {name: (dims, np.full(shape, np.nan), {"description": text}) for name, text in POINT_MEASURES.items()}
    data[ORDER_MEASURE] = ((*dims, "mesh_order"), np.full((*shape, len(MESH_ORDERS)), np.nan),
                           {"description": "single-sided DTE amplitude of mesh orders 1-3 (m)"})
    data["status"] = (dims, np.full(shape, PENDING, np.int8), {"description": "0 pending, 1 done, 2 failed"})
    data["error"] = (dims, np.full(shape, "", f"<U{ERROR_CHARS}"), {"description": "why the point failed"})
    for name, (_, text) in REFERENCE_MEASURES.items():
        data[name] = (ref_dims, np.full(ref_shape, np.nan), {"description": text})
    data["mesh_natural_frequency_hz"] = (ref_dims, np.full(ref_shape, np.nan), {
        "description": "linearized mesh natural frequency sqrt(k (r_b1^2/J1 + r_b2^2/J2))/(2 pi); k: see the "
                       "store's natural_frequency_stiffness"})
    data["tangent_mesh_natural_frequency_hz"] = (ref_dims, np.full(ref_shape, np.nan), {
        "description": "the same with k = reference_mesh_stiffness_n_per_m (mean of the mesh_stiffness output)"})
    data["secant_mesh_natural_frequency_hz"] = (ref_dims, np.full(ref_shape, np.nan), {
        "description": "the same with k = (T1/r_b1) / reference_dte_mean_m (static force over mean DTE)"})
    data["linearized_mesh_frequency_hz"] = (ref_dims, np.full(ref_shape, np.nan), {
        "description": "PMOR-Hertz: the reduced pair's mesh mode linearized over a pitch, sqrt(mean omega^2)/(2 pi) "
                       "(fmu-build linearize): the elastic gears' own linearized model"})
    data["reference_status"] = (ref_dims, np.full(ref_shape, PENDING, np.int8), {"description": "0 pending, 1 done, 2 failed"})
    data["reference_error"] = (ref_dims, np.full(ref_shape, "", f"<U{ERROR_CHARS}"), {})
    ds = xr.Dataset(data, coords={**grid.coords(), "mesh_order": np.asarray(MESH_ORDERS)})
    ds.attrs.update({
        "fmu_name": fmu_name, "fmu_sha256": fmu_sha256, "fmu_description": pair.description,
        # Small oscillations feel the tangent stiffness; the lumped FMU outputs the mesh's. PMOR-Hertz's
        # mesh_stiffness is its Hertz contacts' alone, so there the mean DTE gives the (secant) stiffness.
        "natural_frequency_stiffness": ("tangent: mean of the mesh_stiffness output" if pair.mesh_stiffness_is_whole_mesh
                                        else "linearized: the reduced pair's mesh mode (fmu-build linearize), else "
                                             "secant: static mesh force / mean DTE"),
        "teeth_1": pair.teeth_1, "teeth_2": pair.teeth_2,
        "base_radius_1_m": pair.base_radius_1_m, "base_radius_2_m": pair.base_radius_2_m,
        "parameter_start_values": json.dumps(pair.start_values),
        "recording": json.dumps(recording.as_attrs()),
        "load": "T1 constant on gear 1; viscous -c w2 on gear 2, c = T1 (z2/z1) / w2*; both gears start at the target speeds",
    })
    encoding = {name: {"chunks": chunks + (len(MESH_ORDERS),) if name == ORDER_MEASURE else
                       (chunks if name in POINT_MEASURES or name in ("status", "error") else chunks[1:])}
                for name in ds.data_vars}
    ds.to_zarr(str(path), mode="w-", encoding=encoding, zarr_format=2, consolidated=False)


def pending(path: Path, retry_failed: bool = False) -> tuple[list[tuple], list[tuple]]:
    """Grid indices and reference indices still to compute (FAILED ones too if retry_failed)."""
    group = zarr.open_group(str(path), mode="r")
    todo = (PENDING, FAILED) if retry_failed else (PENDING,)
    points = [tuple(int(i) for i in index) for index in np.argwhere(np.isin(group["status"][...], todo))]
    references = [tuple(int(i) for i in index) for index in np.argwhere(np.isin(group["reference_status"][...], todo))]
    return points, references


class Writer:
    """Writes results into the store a batch (one returned chunk) at a time, status last.

    Each variable is written for the whole batch in one call (zarr's vectorized index), which
    writes the points' chunk files concurrently; the status of the batch follows all of them.
    """

    def __init__(self, path: Path):
        group = zarr.open_group(str(path), mode="r+")
        self.arrays = {name: array for name, array in group.arrays()}   # open each array once
        self.attrs = dict(group.attrs)
        self.start_values = json.loads(self.attrs["parameter_start_values"])

    def _set(self, name: str, indices: list[tuple], values) -> None:
        if indices:
            self.arrays[name].vindex[tuple(np.array(indices).T)] = np.asarray(values)

    def write_points(self, batch: list[tuple[tuple, dict]]) -> None:
        """batch: [(grid index, result), …]."""
        done = [(index, result) for index, result in batch if not result.get("error")]
        failed = [(index, result) for index, result in batch if result.get("error")]
        done_at, failed_at = [i for i, _ in done], [i for i, _ in failed]
        for name in POINT_MEASURES:
            self._set(name, done_at, [r[name] for _, r in done])
        # The order amplitudes have one more axis: one coordinate per (point, order).
        self._set(ORDER_MEASURE, [(*i, k) for i in done_at for k in range(len(MESH_ORDERS))],
                  [a for _, r in done for a in r[ORDER_MEASURE]])
        self._set("error", done_at, [""] * len(done))
        self._set("wall_s", failed_at, [r["wall_s"] for _, r in failed])
        self._set("error", failed_at, [r["error"][:ERROR_CHARS] for _, r in failed])
        self._set("status", done_at, [DONE] * len(done))
        self._set("status", failed_at, [FAILED] * len(failed))

    def write_references(self, batch: list[tuple[tuple, dict, dict]]) -> None:
        """batch: [((torque, *parameter indices), parameters, result), …]. The linearized f_n uses
        the inertias in force at the point."""
        done = [(i, p, r) for i, p, r in batch if not r.get("error")]
        failed = [(i, r) for i, _, r in batch if r.get("error")]
        done_at, failed_at = [i for i, _, _ in done], [i for i, _ in failed]
        for name, (source, _) in REFERENCE_MEASURES.items():
            self._set(name, done_at, [r[source] for _, _, r in done])
        tangent, secant = [], []
        for _, parameters, result in done:
            inertias = {**self.start_values, **parameters}

            def f_n(stiffness: float) -> float:
                return mesh_natural_frequency_hz(stiffness, self.attrs["base_radius_1_m"], self.attrs["base_radius_2_m"],
                                                 inertias["inertia_1"], inertias["inertia_2"])

            tangent.append(f_n(result["mesh_stiffness_mean_n_per_m"]))
            secant.append(f_n(result["static_mesh_force_n"] / result["dte_mean_m"]))
        self._set("tangent_mesh_natural_frequency_hz", done_at, tangent)
        self._set("secant_mesh_natural_frequency_hz", done_at, secant)
        use_tangent = self.attrs["natural_frequency_stiffness"].startswith("tangent")
        linearized = self.arrays["linearized_mesh_frequency_hz"]
        self._set("mesh_natural_frequency_hz", done_at,
                  tangent if use_tangent else
                  [lin if np.isfinite(lin := float(linearized[i])) else sec for i, sec in zip(done_at, secant)])
        self._set("reference_error", done_at, [""] * len(done))
        self._set("reference_error", failed_at, [r["error"][:ERROR_CHARS] for _, r in failed])
        self._set("reference_status", done_at, [DONE] * len(done))
        self._set("reference_status", failed_at, [FAILED] * len(failed))


    def write_linearized(self, frequencies: dict) -> None:
        """{reference index: the linearized mesh frequency (Hz)}: stored, and taken as the f_n of
        those references (already written or not)."""
        indices = list(frequencies)
        self._set("linearized_mesh_frequency_hz", indices, [frequencies[i] for i in indices])
        done = [i for i in indices if self.arrays["reference_status"][i] == DONE]
        self._set("mesh_natural_frequency_hz", done, [frequencies[i] for i in done])


def load(path: Path) -> xr.Dataset:
    """The whole store as an in-memory Dataset."""
    # chunks=None: plain NumPy reads; one Dask task per one-point chunk would cost more than the data.
    with xr.open_zarr(str(path), consolidated=False, chunks=None) as ds:
        return ds.load()

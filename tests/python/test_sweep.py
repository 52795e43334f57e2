"""The sweep package (python/gearfmu, issue 14) against closed forms and against itself.

* The DFT of mesh orders and the linearized mesh natural frequency against closed forms (the
  latter against fmu-build's own figure, computed in Rust).
* Dask: a LocalCluster with 2 workers gives bit for bit the store of a serial run; a worker killed
  while it runs a point loses nothing (Dask reruns its chunk; the client writes the store).
* Physics: where contact is never lost (the helical pair, light excitation, 10 % damping) the
  resonance sits within 5 % of f_n = sqrt(k_mean (r_b1²/J1 + r_b2²/J2)) / 2π, with k_mean the
  FMU's mean mesh stiffness at a quasi-static point, and the 1/2 sub-harmonic shows; where it is
  lost (the spur pair at 5 %), the peak moves down (softening) and the curve jumps.
* PMOR-Hertz: a point reaching the coast flank is stored with the FMU's error, never lost.

Every sweep here reuses the FMUs of the session fixture ``gear_fmus``.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from gearfmu import store
from gearfmu.operating_point import mesh_natural_frequency_hz, mesh_order_amplitudes
from gearfmu.store import Grid
from gearfmu.sweep import linearized_mesh_frequencies, sweep

MODEL_MEASURES = [name for name in (*store.POINT_MEASURES, store.ORDER_MEASURE, *store.REFERENCE_MEASURES,
                                    "mesh_natural_frequency_hz",
                                    "tangent_mesh_natural_frequency_hz", "secant_mesh_natural_frequency_hz", "status", "reference_status", "error")
                  if name not in store.TIMINGS]


def rpm_for_mesh_frequency(f_m_hz: float, teeth_1: int) -> float:
    return 60.0 * f_m_hz / teeth_1


def test_mesh_order_amplitudes_recover_a_sum_of_mesh_harmonics():
    cycles, per_cycle = 10, 64
    theta = 2.0 * math.pi * np.arange(cycles * per_cycle) / per_cycle     # mesh phase
    signal = 7.0 + 3.0 * np.cos(theta + 0.4) + 0.5 * np.sin(2 * theta) + 0.25 * np.cos(3 * theta - 1.0) \
        + 0.8 * np.cos(0.5 * theta)                                       # a sub-harmonic: not an order
    np.testing.assert_allclose(mesh_order_amplitudes(signal, cycles), [3.0, 0.5, 0.25], rtol=1e-12)


def test_mesh_natural_frequency_matches_fmu_builds(gear_fmus):
    for case in (gear_fmus["spur"], gear_fmus["helical"]):
        m = case.mesh
        f_n = mesh_natural_frequency_hz(m["reference_stiffness_n_per_m"], m["base_radius_1_m"],
                                        m["base_radius_2_m"], m["inertia_1_kgm2"], m["inertia_2_kgm2"])
        assert f_n == pytest.approx(m["mesh_natural_frequency_hz"], rel=1e-9)


def assert_same_results(a, b):
    for name in MODEL_MEASURES:
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


def test_two_workers_equal_serial_bit_for_bit_and_a_killed_worker_loses_no_point(gear_fmus, tmp_path):
    from dask.distributed import Client, LocalCluster

    fmu = gear_fmus["spur"].fmu_path
    teeth_1 = gear_fmus["spur"].mesh["teeth_1"]
    # Low mesh frequencies: each point takes ~0.1-0.3 s, so a worker is surely inside one when killed.
    speeds = tuple(rpm_for_mesh_frequency(f, teeth_1) for f in (150.0, 250.0, 400.0, 600.0, 900.0, 1300.0))
    grid = Grid(speeds, (100.0, 370.0))
    serial = sweep(fmu, grid, tmp_path / "serial.zarr", serial=True, progress=False)
    assert (serial["status"].values == store.DONE).all()
    assert (serial["reference_status"].values == store.DONE).all()

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        clean = sweep(fmu, grid, tmp_path / "clean.zarr", client=client, chunk_size=1, progress=False)
        assert_same_results(serial, clean)

        killed = []

        def kill_a_busy_worker(_points_written):
            if killed:
                return
            busy = [address for address, keys in client.processing().items() if keys]
            assert busy, "no worker was running a point"
            pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
            os.kill(pid, 9)                                   # SIGKILL: no goodbye to the scheduler
            killed.append(pid)

        interrupted = sweep(fmu, grid, tmp_path / "killed.zarr", client=client, chunk_size=1, progress=False,
                            on_chunk=kill_a_busy_worker)
        assert killed
        # Dask reran the killed worker's chunk; if it had given up, a second run finishes the store.
        if (interrupted["status"].values == store.PENDING).any():
            interrupted = sweep(fmu, grid, tmp_path / "killed.zarr", client=client, chunk_size=1, progress=False)
        assert_same_results(serial, interrupted)

    # Resuming a complete store runs nothing and changes nothing.
    again = sweep(fmu, grid, tmp_path / "serial.zarr", serial=True, progress=False,
                  on_chunk=lambda n: pytest.fail("a finished point was run again"))
    assert_same_results(serial, again)
    np.testing.assert_array_equal(serial["wall_s"].values, again["wall_s"].values)


def linear_regime_sweep(case, tmp_path, fractions, torque_nm, damping):
    f_n_guess = case.mesh["mesh_natural_frequency_hz"]       # only to place the grid
    speeds = tuple(rpm_for_mesh_frequency(x * f_n_guess, case.mesh["teeth_1"]) for x in fractions)
    grid = Grid(speeds, (torque_nm,), {"mesh_damping_ratio": (damping,)})
    ds = sweep(case.fmu_path, grid, tmp_path / f"{case.name}.zarr", serial=True, progress=False)
    assert (ds["status"].values == store.DONE).all()
    return ds.isel(torque_nm=0, mesh_damping_ratio=0)


def test_resonance_within_5_percent_of_the_linearized_mesh_frequency_where_contact_holds(gear_fmus, tmp_path):
    """Helical pair (total contact ratio > 2: a small stiffness ripple, light excitation), ζ = 0.1."""
    case = gear_fmus["helical"]
    fractions = [0.425, 0.45, 0.475, 0.49, 0.5, 0.51, 0.525, 0.55, 0.575,
                 0.85, 0.9, 0.93, 0.95, 0.97, 0.985, 1.0, 1.015, 1.03, 1.05, 1.07, 1.1, 1.15]
    ds = linear_regime_sweep(case, tmp_path, fractions, 370.0, 0.1)
    f_n = float(ds["mesh_natural_frequency_hz"])           # from the FMU's own mesh_stiffness output
    f_m = ds["mesh_frequency_hz"].values
    assert (ds["contact_loss_share"].values == 0.0).all()
    assert (ds["settled"].values == 1).all()
    # The drive holds the target speed (the load balances the drive at it): mean ω₁ to 0.1 %.
    np.testing.assert_allclose(ds["speed_1_mean_rpm"].values, ds["speed_rpm"].values, rtol=1e-3)

    main = f_m > 0.7 * f_n
    rms = ds["dte_rms_m"].values
    peak = f_m[main][np.argmax(rms[main])]
    assert abs(peak / f_n - 1.0) < 0.05, (peak, f_n)
    # A peak, not a slope: an interior maximum well above both ends. A linear oscillator at ζ = 0.1
    # gives |H(1)| / |H(0.85)| = 1.63 and |H(1)| / |H(1.15)| = 2.5 for a constant excitation.
    assert 0 < np.argmax(rms[main]) < main.sum() - 1
    assert rms[main].max() > 1.5 * rms[main][[0, -1]].max()

    sub = ~main                                                          # f_m near f_n / 2
    second_order = ds["dte_order_amplitude_m"].values[:, 1]
    sub_peak = f_m[sub][np.argmax(second_order[sub])]
    assert abs(2.0 * sub_peak / f_n - 1.0) < 0.05, (sub_peak, f_n)
    assert 0 < np.argmax(second_order[sub]) < sub.sum() - 1
    assert second_order[sub].max() > 1.5 * second_order[sub][[0, -1]].max()


def test_contact_loss_softens_the_resonance_and_makes_it_jump(gear_fmus, tmp_path):
    """Spur pair at its default 5 % damping: the dynamic DTE exceeds the static deflection."""
    case = gear_fmus["spur"]
    fractions = list(np.arange(0.6, 1.16, 0.025))
    ds = linear_regime_sweep(case, tmp_path, fractions, 185.0, 0.05)
    f_n = float(ds["mesh_natural_frequency_hz"])
    f_m, rms, loss = ds["mesh_frequency_hz"].values, ds["dte_rms_m"].values, ds["contact_loss_share"].values
    assert loss.max() > 0.2                                  # the store keeps the contact-loss share
    peak = f_m[np.argmax(rms)]
    assert peak < 0.9 * f_n, (peak, f_n)                     # softening: the peak leans to lower f_m
    assert loss[np.argmax(rms)] > 0.0
    assert np.max(rms[1:] / rms[:-1]) > 2.0                  # the jump onto the contact-loss branch


def test_a_failed_point_is_stored_with_the_fmus_error_and_retried_on_request(gear_fmus, tmp_path):
    """max_step = 1 ms is beyond RK4's stability limit on the mesh mode: the FMU refuses it at
    fmi2ExitInitializationMode. Those points are FAILED with the FMU's logged reason; the others
    are unaffected (the instance is reset between points); a re-run skips them unless asked."""
    case = gear_fmus["spur"]
    grid = Grid((3000.0, 6000.0), (185.0,), {"max_step": (1e-5, 1e-3)})
    ds = sweep(case.fmu_path, grid, tmp_path / "failing.zarr", serial=True, progress=False)
    good, bad = ds.sel(max_step=1e-5), ds.sel(max_step=1e-3)
    assert (good["status"].values == store.DONE).all() and (good["error"].values == "").all()
    assert (bad["status"].values == store.FAILED).all()
    assert (bad["reference_status"].values == store.FAILED).all()
    for error in bad["error"].values.ravel():
        assert "fmi2ExitInitializationMode" in error and "max_step" in error.split("FMU log:")[1], error
    assert np.isnan(bad["dte_rms_m"].values).all()

    runs = []
    sweep(case.fmu_path, grid, tmp_path / "failing.zarr", serial=True, progress=False, on_chunk=runs.append)
    assert runs == []
    sweep(case.fmu_path, grid, tmp_path / "failing.zarr", serial=True, progress=False, on_chunk=runs.append,
          retry_failed=True)
    assert sum(runs) == 3                                  # two points and their reference, failing again


def test_pmor_hertz_at_its_resonance_loses_contact_undamped_and_holds_it_with_the_mesh_damper(gear_fmus, tmp_path):
    """PMOR-Hertz at its mesh resonance (f_m = 0.95 of its linearized mesh mode, where the ζ = 0.2
    sweep in BENCHMARKS peaks), 185 N·m. The paper's model (modal damping only: the mesh mode at
    0.36 %, `fmu-build linearize`) loses contact there: the softening branch. The mesh damper at
    ζ = 0.2 holds contact. Both points are stored DONE, the contact-loss share with them, and the
    store's f_n is the reduced pair's own linearized mesh mode (~14 s per point and reference)."""
    case = gear_fmus["spur-pmor"]
    f_lin = linearized_mesh_frequencies(case.fmu_path, Grid((0.0,), (185.0,)))[(0,)]
    # Against an independent estimate: the lumped model's rigid two-inertia f_n (inspect, its own
    # mean mesh stiffness) is lower — the PMOR-Hertz gears' rims and webs move with the teeth, so
    # less inertia takes part — but not by more than 20 %.
    assert 1.0 < f_lin / case.mesh["mesh_natural_frequency_hz"] < 1.2, (f_lin, case.mesh["mesh_natural_frequency_hz"])
    grid = Grid((rpm_for_mesh_frequency(0.95 * f_lin, case.mesh["teeth_1"]),), (185.0,),
                {"mesh_damping_ratio": (0.0, 0.2)})
    ds = sweep(case.fmu_path, grid, tmp_path / "pmor.zarr", serial=True, progress=False)
    assert (ds["status"].values == store.DONE).all(), ds["error"].values
    assert ds.attrs["natural_frequency_stiffness"].startswith("linearized")
    np.testing.assert_array_equal(ds["mesh_natural_frequency_hz"].values.ravel(), [f_lin, f_lin])
    loss = ds["contact_loss_share"].isel(speed_rpm=0, torque_nm=0)
    assert float(loss.sel(mesh_damping_ratio=0.0)) > 0.2
    assert float(loss.sel(mesh_damping_ratio=0.2)) == 0.0
    rms = ds["dte_rms_m"].isel(speed_rpm=0, torque_nm=0)
    assert float(rms.sel(mesh_damping_ratio=0.0)) > 2.0 * float(rms.sel(mesh_damping_ratio=0.2))

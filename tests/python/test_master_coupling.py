"""A master couples to the gear FMU's ports explicitly, as every FMI master does: it reads the
ports' angles and speeds at a communication point and holds the torques it computes from them
over the step. Two loops a drivetrain engineer writes first (issue 24's grids):

* the paper's example 3: 185 N·m on gear 1 (5 ms haversine), a viscous brake of 20 N·m·s/rad on
  gear 2 fed back from ``w_2``; at every communication step from 1 µs to 1 ms it must complete
  and reach the closed-form steady speed ω₂ = T₁·z₂/(z₁·c) (mean over the last 5 ms, 0.5 %);
* a motor inertia driving gear 1 through a torsional spring–damper the master integrates
  (stiffness 1e4–1e6 N·m/rad), the same brake on gear 2: the PMOR-Hertz FMU must complete
  wherever the lumped FMU (rigid gears: the coupling's own stability) completes.

Both run with the mesh damper off too (``mesh_damping_ratio`` = 0): before the ports were the
gears' mean axes, the bore's 40–60 kHz hub mode made the brake loop diverge at 9–11 µs and the
shaft loop at 10 µs for every stiffness there, and only the rigid-frame damper hid it.
"""

from __future__ import annotations

import functools
import math

import pytest
from conftest import GearSlave

TORQUE_NM, RAMP_S, BRAKE, END_S = 185.0, 5e-3, 20.0, 25e-3


def teeth(case) -> tuple[int, int]:
    from fmpy import read_model_description
    md = read_model_description(str(case.fmu_path))
    z1, z2 = md.description.split("(z ", 1)[1].split(")", 1)[0].split("/")
    return int(z1), int(z2)


def ramp(t: float) -> float:
    return TORQUE_NM * (0.5 - 0.5 * math.cos(math.pi * t / RAMP_S) if t < RAMP_S else 1.0)


def brake_run(slave: GearSlave, h: float) -> tuple[list[float], list[float]]:
    """Example 3 at communication step h; ω₂ and φ₂ at every step end."""
    w_2, speeds, angles = 0.0, [], []
    for k in range(int(round(END_S / h))):
        slave.set_inputs(ramp(k * h), -BRAKE * w_2)
        slave.step(k * h, h)
        w_2, phi_2 = slave.fmu.getReal([slave.vr["w_2"], slave.vr["phi_2"]])
        speeds.append(w_2)
        angles.append(phi_2)
    return speeds, angles


@pytest.mark.parametrize("zeta", [0.0, None], ids=["no-mesh-damper", "default"])
def test_example_3_brake_loop_completes_at_every_communication_step(gear_fmus, zeta):
    case = gear_fmus["spur-pmor"]
    failures = []
    for h_us in (1, 2, 5, 9, 10, 11, 20, 50, 100, 1000):
        h = h_us * 1e-6
        params = {} if zeta is None else {"mesh_damping_ratio": zeta}
        slave = GearSlave(case, f"brake-{h_us}", parameters=params)
        z1, z2 = teeth(case)
        try:
            speeds, angles = brake_run(slave, h)
        except Exception as e:  # fmpy raises on fmi2Error
            failures.append(f"{h_us} µs: {e}")
            continue
        finally:
            slave.free()
        # The mean over the last 5 ms is the angle travelled over them: at 1 ms the five speed
        # samples alias the mesh mode's ringing (without a mesh damper ±2 rad/s at 3.6 kHz:
        # their mean is 0.73 % low where the angle's is 0.26 %), which is not the mean.
        n = max(1, int(round(5e-3 / h)))
        mean, closed_form = (angles[-1] - angles[-1 - n]) / (n * h), TORQUE_NM * z2 / (z1 * BRAKE)
        sampled = sum(speeds[-n:]) / n
        print(f"h = {h_us} µs: mean ω₂ {mean:.5f} rad/s (of the samples {sampled:.5f}), closed form {closed_form:.5f} ({mean / closed_form - 1:+.2e})")
        # Without a mesh damper at 1 ms the mean is not the model's to keep: the brake is fed
        # the aliased samples of an undamped mesh-mode ringing, and the coupled system's mean
        # speed follows the ringing's phase at the sample instants. Measured with the FMU's own
        # internal step made finer (example pair, 2026-11-27): discrete gradient at 20 / 10 / 5
        # / 2 µs +1.22 / +1.06 / −0.65 / −0.94 %, velocity Verlet at 20 / 2 µs −0.26 / −1.55 %:
        # no converged value within 0.5 % exists. There the run must complete (stability).
        if zeta == 0.0 and h_us == 1000:
            continue
        if abs(mean / closed_form - 1.0) > 5e-3:
            failures.append(f"{h_us} µs: mean ω₂ {mean} against {closed_form}")
    assert not failures, failures


def shaft_run(slave: GearSlave, teeth_: tuple[int, int], stiffness: float, h: float, motor_inertia: float = 0.01) -> float:
    """Motor (inertia, torque ramp) → torsional spring–damper → gear 1; brake on gear 2. The
    master integrates the motor by symplectic Euler and couples explicitly (Jacobi). The shaft
    damper gives its two-inertia mode 5 % of critical. Returns ω₂ at the end."""
    z1, z2 = teeth_
    j1, j2 = slave.fmu.getReal([slave.vr["inertia_1"], slave.vr["inertia_2"]])
    gear_side = j1 + j2 * (z1 / z2) ** 2
    reduced = motor_inertia * gear_side / (motor_inertia + gear_side)
    damper = 2 * 0.05 * math.sqrt(stiffness * reduced)
    phi_m = w_m = 0.0
    speeds = []
    for k in range(int(round(END_S / h))):
        phi_1, w_1, w_2 = slave.fmu.getReal([slave.vr[n] for n in ("phi_1", "w_1", "w_2")])
        shaft = stiffness * (phi_m - phi_1) + damper * (w_m - w_1)
        slave.set_inputs(shaft, -BRAKE * w_2)
        slave.step(k * h, h)
        w_m += h * (ramp(k * h) - shaft) / motor_inertia
        phi_m += h * w_m
        speeds.append(slave.fmu.getReal([slave.vr["w_2"]])[0])
    last = speeds[-int(round(5e-3 / h)):]
    return sum(last) / len(last)


def test_shaft_loop_completes_wherever_the_rigid_gears_complete(gear_fmus):
    outcome = {}
    for name, zeta in (("spur", None), ("spur-pmor", None), ("spur-pmor", 0.0)):
        case = gear_fmus[name]
        for stiffness in (1e4, 1e5, 1e6):
            for h_us in (10, 50, 100):
                params = {} if zeta is None else {"mesh_damping_ratio": zeta}
                slave = GearSlave(case, f"shaft-{name}-{stiffness:g}-{h_us}", parameters=params)
                try:
                    result = shaft_run(slave, teeth(case), stiffness, h_us * 1e-6)
                except Exception:
                    result = None
                finally:
                    slave.free()
                outcome[(name, zeta, stiffness, h_us)] = result
                print(name, zeta, stiffness, h_us, result)
    for (name, zeta, stiffness, h_us), result in outcome.items():
        rigid = outcome[("spur", None, stiffness, h_us)]
        if name == "spur-pmor" and rigid is not None:
            assert result is not None, f"PMOR-Hertz (ζ = {zeta}) failed at k = {stiffness:g}, h = {h_us} µs where the lumped FMU completes"
        if result is not None:
            # The steady speed is the brake's, whatever the gear model (closed form).
            z1, z2 = teeth(gear_fmus[name])
            closed_form = TORQUE_NM * z2 / (z1 * BRAKE)
            assert abs(result / closed_form - 1.0) < 5e-3, (name, zeta, stiffness, h_us, result, closed_form)
    # The grid is not vacuous: the loop itself is stable at the smaller stiffnesses.
    assert all(outcome[("spur", None, k, 10)] is not None for k in (1e4, 1e5, 1e6))


@pytest.mark.parametrize("model", ["spur-pmor", "spur"])
def test_example_3_through_libcosim_matches_fmpy(gear_fmus, model):
    """A second, industrial master (DNV's libcosim, Open Simulation Platform, through
    libcosimpy) runs example 3 on both gear models (PMOR-Hertz and lumped): the same explicit
    brake loop at 0.1 ms, its override manipulator writing the torques and its last-value
    observer reading ω₂. The DTE and ω₂ agree with the fmpy loop to 1e-9 relative (of their
    ranges) at every step (issue 29: libcosim's h, a difference of times, no longer flips the
    lumped FMU's sub-step count)."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.WARNING)
    case, h, steps = gear_fmus[model], 1e-4, 250
    execution = CosimExecution.from_step_size(step_size=int(round(h * 1e9)))
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(case.fmu_path), instance_name="pair"))
    manipulator, observer = CosimManipulator.create_override(), CosimObserver.create_last_value()
    execution.add_manipulator(manipulator=manipulator)
    execution.add_observer(observer=observer)
    refs = {v.name.decode(): v.reference for v in execution.slave_variables(slave_index=index)}
    cosim = []
    for k in range(steps):
        w_2 = observer.last_real_values(slave_index=index, variable_references=[refs["w_2"]])[0] if k else 0.0
        manipulator.slave_real_values(index, [refs["tau_1"], refs["tau_2"]], [ramp(k * h), -BRAKE * w_2])
        assert execution.step(), f"libcosim step {k} failed"
        cosim.append(observer.last_real_values(slave_index=index, variable_references=[refs["w_2"], refs["dte"]]))

    slave = GearSlave(case, "fmpy-example-3")
    reference, w_2 = [], 0.0
    for k in range(steps):
        slave.set_inputs(ramp(k * h), -BRAKE * w_2)
        slave.step(k * h, h)
        w_2, dte = slave.fmu.getReal([slave.vr["w_2"], slave.vr["dte"]])
        reference.append((w_2, dte))
    slave.free()
    for column in range(2):
        a, b = [r[column] for r in cosim], [r[column] for r in reference]
        scale = max(b) - min(b)
        worst = max(abs(x - y) for x, y in zip(a, b)) / scale
        print(f"{('ω₂', 'DTE')[column]}: libcosim against fmpy, largest difference {worst:.2e} of the range")
        assert worst < 1e-9


QUASI_STATIC_TORQUES = (22.0, 185.0, 370.0)


def _ste_figures(case, torques=QUASI_STATIC_TORQUES, angles=40) -> dict:
    """`fmu-build ste` on the FMU's own spec and mesh at the quasi-static torques: per torque the
    mean and peak-to-peak STE (µm) and, for a spur pair, the single- and double-contact zones'
    mean STE (µm). One run per spec, torques and angles for the session (the lumped and the
    PMOR-Hertz FMU of a spec share it)."""
    return _ste_of_spec(str(case.spec_path), tuple(torques), angles)


@functools.lru_cache(maxsize=None)
def _ste_of_spec(spec: str, torques: tuple, angles: int) -> dict:
    import re
    from conftest import _fmu_build

    out = _fmu_build("ste", spec, "--torque-nm", ",".join(str(t) for t in torques),
                     "--angles", str(angles)).stdout
    figures = {}
    for block in out.split("pmor-hertz T₁ ")[1:]:
        torque = float(block.split(" ", 1)[0])
        found = re.search(r"mean STE ([0-9.]+) µm, peak-to-peak ([0-9.]+) µm", block)
        assert found, out
        zones = re.search(r"single contact mean STE ([0-9.]+) µm \(\d+ positions\), double ([0-9.]+) µm", block)
        figures[torque] = {
            "mean": float(found.group(1)), "p-p": float(found.group(2)),
            "zones": {1: float(zones.group(1)), 2: float(zones.group(2))} if zones else None,
        }
    assert sorted(figures) == sorted(torques), out
    return figures


@pytest.mark.parametrize("kind", ["spur-pmor", "spur", "helical"])
def test_quasi_static_dte_reproduces_the_static_transmission_error(gear_fmus, kind):
    """Slow limit with the FMU's defaults (evidence: the PMOR-Hertz statics, `fmu-build ste`, on
    the FMU's own spec and mesh), for the PMOR-Hertz FMU and the lumped one (its mesh law taken
    from those statics, the default; issue 26): under T₁ = 22, 185 and 370 N·m the pair starts
    in its static equilibrium (``start_at_equilibrium``) rolling at ω₂ = 0.3 rad/s, and a speed
    controller on gear 2 (the balancing torque −T₁z₂/z₁ and a feedback on the speed error) holds
    the mean ω₂ within 0.5 % of it. Over
    the last mesh cycle the DTE, smoothed by a 2 ms moving average, has the static mean within
    2 % and peak-to-peak within 5 %; on a spur pair also zone by zone: the mean over the positions
    where one and where two tooth pairs carry the load (the FMU's ``contact_pairs`` constant over
    the window) within 2 % of the statics' zone means."""
    _quasi_static_check(gear_fmus[kind], QUASI_STATIC_TORQUES)


def test_quasi_static_dte_of_the_helical_pmor_fmu_reproduces_the_static_transmission_error(gear_fmus):
    """Issue 40, Build 4: the Kurokawa helical pair's PMOR-Hertz FMU (defaults, built in CI now
    that it builds in under a minute) in the same slow limit at the design torque, 185 N·m
    (evidence: the PMOR-Hertz statics of its spec and mesh, `fmu-build ste`, the run the lumped
    helical FMU's check makes): DTE mean within 2 % and peak-to-peak within 5 % of the STE's
    (measured once before: 0.2 % and 4.2 %). No zone check: a helical pair's contact lines
    change length continuously, with no constant count of tooth pairs to average over."""
    _quasi_static_check(gear_fmus["helical-pmor"], (185.0,), ste_torques=QUASI_STATIC_TORQUES)


def test_quasi_static_dte_of_the_relieved_pair_follows_its_static_transmission_error(relieved_fmus):
    """Flank modifications reach both FMUs (issue 27; evidence: the PMOR-Hertz statics of the
    relieved spec, `fmu-build ste`): the spur pair with 12 µm of long tip relief (the Harris
    optimum at 185 N·m) and 3 µm of lead crowning, at its design load. Each FMU's quasi-static
    DTE has the relieved STE's mean (2 %), peak-to-peak (5 %) and single- and double-contact
    zone means (2 %), as the unmodified pair's do; so the lumped and the PMOR-Hertz FMU agree
    zone by zone through the same statics. The statics take 160 positions: the relieved STE's
    extremes are narrow (the hand-overs), and 40 positions miss 7 % of its peak-to-peak
    (1.211 against 1.292 µm)."""
    zones = {}
    for kind in ("relieved-pmor", "relieved"):
        zones[kind] = _quasi_static_check(relieved_fmus[kind], (185.0,), angles=160)[185.0]
    print("relieved pair at 185 N·m, PMOR-Hertz / lumped: " + "; ".join(
        f"{key} {zones['relieved-pmor'][key]:.3f} / {zones['relieved'][key]:.3f} µm" for key in zones["relieved"]))


def _quasi_static_check(case, torques, angles=40, ste_torques=None) -> dict:
    """The slow-limit run and its checks (above) at each torque; per torque the DTE's mean,
    peak-to-peak and zone means (µm). `ste_torques`: the statics' torques when more than those
    run (a statics run another check of the same spec makes)."""
    import numpy as np

    ste = _ste_figures(case, ste_torques or torques, angles)
    # Issue 41: the pair starts in its static equilibrium (no ramp, no settling) and a speed
    # controller on gear 2 holds ω₂: the balancing torque −T₁z₂/z₁ fed forward plus a gain of
    # 200 N·m·s/rad on the speed error. (Open-loop the pair rolls over the STE's hills: at
    # 0.3 rad/s the work F·ΔSTE of a hand-over is a third of the kinetic energy, ω₂ −8 %.) The
    # viscous brake of before was this controller with a gain of T₁z₂/(z₁ω₂), up to 1820
    # N·m·s/rad, whose explicit loop needed 5 µs steps: 150 000 Python round trips per torque.
    # The explicit loop is stable for h < 2J/c ≈ 0.2 ms: 50 µs.
    speed, gain, h = 0.3, 200.0, 5e-5
    z1, z2 = teeth(case)
    cycle = 2 * math.pi / z2 / speed
    figures = {}
    for torque in torques:
        balance = -torque * z2 / z1
        slave = GearSlave(case, f"quasi-static-{torque}", booleans={"start_at_equilibrium": True},
                          parameters={"w_1_start": speed * z2 / z1, "w_2_start": speed},
                          inputs=(torque, balance))
        w_2, t, rows = speed, 0.0, []
        for _ in range(int((0.01 + 1.05 * cycle) / h)):
            slave.set_inputs(torque, balance - gain * (w_2 - speed))
            slave.step(t, h)
            t += h
            w_2, dte = slave.fmu.getReal([slave.vr["w_2"], slave.vr["dte"]])
            rows.append((t, w_2, dte, slave.fmu.getInteger([slave.vr["contact_pairs"]])[0]))
        slave.free()
        a = np.array(rows)
        last = a[a[:, 0] > a[-1, 0] - cycle]
        window = int(round(2e-3 / h))
        smooth = np.convolve(last[:, 2], np.ones(window) / window, mode="valid")
        mean, peak_to_peak = smooth.mean() * 1e6, (smooth.max() - smooth.min()) * 1e6
        reference = ste[torque]
        kind = case.name
        figures[torque] = {"mean": mean, "p-p": peak_to_peak}
        line = (f"{kind} T₁ {torque:g} N·m: ω₂ {last[:, 1].mean():.4f} rad/s; DTE mean {mean:.3f} µm "
                f"(ste {reference['mean']}), p-p {peak_to_peak:.3f} µm (ste {reference['p-p']})")
        assert abs(last[:, 1].mean() / speed - 1.0) < 5e-3, line
        assert abs(mean / reference["mean"] - 1.0) < 0.02, line
        assert abs(peak_to_peak / reference["p-p"] - 1.0) < 0.05, line
        if reference["zones"] is not None:
            pairs = last[:, 3]
            counts = np.lib.stride_tricks.sliding_window_view(pairs, window)
            steady = counts.min(axis=1) == counts.max(axis=1)
            for n, static in reference["zones"].items():
                inside = steady & (counts[:, 0] == n)
                assert inside.sum() > window, f"{line}: no steady {n}-pair zone"
                zone = smooth[inside].mean() * 1e6
                figures[torque][f"{n}-pair zone"] = zone
                line += f"; {n}-pair zone {zone:.3f} µm (ste {static})"
                assert abs(zone / static - 1.0) < 0.02, line
        print(line)
    return figures


@pytest.mark.parametrize("kind", ["spur-pmor", "spur"])
def test_start_at_equilibrium_through_fmpy(gear_fmus, kind):
    """``start_at_equilibrium`` through a second FMI client (fmpy's fmi2SetBoolean; evidence: a
    static equilibrium is a fixed point). At rest under balanced torques from t = 0 the DTE
    stays within 1e-4 of its static value over 1 ms; from the undeformed start the same
    torques strike the teeth (a swing above half the static DTE). Lumped and PMOR-Hertz."""
    case = gear_fmus[kind]
    z1, z2 = teeth(case)
    torque = 185.0

    def run(equilibrium: bool) -> tuple[float, float]:
        from fmpy import read_model_description
        from fmpy.fmi2 import FMU2Slave

        md = read_model_description(str(case.fmu_path))
        vr = {v.name: v.valueReference for v in md.modelVariables}
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=str(case.unzip_dir),
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName=f"equilibrium-{equilibrium}")
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setBoolean([vr["start_at_equilibrium"]], [equilibrium])
        assert fmu.getBoolean([vr["start_at_equilibrium"]]) == [equilibrium]
        # Balanced: the base radii are in the ratio of the teeth.
        fmu.setReal([vr["tau_1"], vr["tau_2"]], [torque, -torque * z2 / z1])
        fmu.exitInitializationMode()
        dte = [fmu.getReal([vr["dte"]])[0]]
        for k in range(100):
            fmu.doStep(currentCommunicationPoint=k * 1e-5, communicationStepSize=1e-5)
            dte.append(fmu.getReal([vr["dte"]])[0])
        fmu.terminate()
        fmu.freeInstance()
        return dte[0], max(dte) - min(dte)

    static, swing = run(True)
    _, cold_swing = run(False)
    print(f"{kind}: static DTE {static * 1e6:.4f} µm, swing {swing * 1e6:.2e} µm; cold start swing {cold_swing * 1e6:.3f} µm")
    assert static > 0.0
    assert swing < 1e-4 * static
    assert cold_swing > 0.5 * static


def test_example_3_lumped_and_pmor_hertz_agree_but_for_the_body_modes(gear_fmus):
    """Two fidelity levels, one answer (issue 26; evidence: the PMOR-Hertz FMU, the lumped FMU
    fed by the same FE statics, one script, one loop). Example 3 at a 20 µs communication step:
    over the last mesh cycle the DTE means agree within 2 % (measured 0.09 %). What differs
    is dynamic, and it is what the lumped level leaves out: after the ramp (t > 8 ms) at least
    70 % of the difference's power (measured 82 %) lies between 2 and 4.2 kHz, where the
    PMOR-Hertz pair has its body modes (2.36–2.83 kHz, ζ 1 %, `fmu-build linearize`) next to the
    mesh mode (3.0–3.7 kHz) that both carry; the rest below it (the tables' interpolation at the
    mesh frequency's harmonics)."""
    import numpy as np

    h = 2e-5
    steps = int(round(END_S / h))
    dte = {}
    for kind in ("spur-pmor", "spur"):
        slave = GearSlave(gear_fmus[kind], f"example-3-{kind}")
        w_2, rows = 0.0, []
        for k in range(steps):
            slave.set_inputs(ramp(k * h), -BRAKE * w_2)
            slave.step(k * h, h)
            w_2, d = slave.fmu.getReal([slave.vr["w_2"], slave.vr["dte"]])
            rows.append(((k + 1) * h, w_2, d))
        slave.free()
        dte[kind] = np.array(rows)
    t = dte["spur"][:, 0]
    z1, z2 = teeth(gear_fmus["spur"])
    # The last mesh cycle of gear 2 (its angle is the integral of ω₂).
    phi_2 = np.cumsum(dte["spur-pmor"][:, 1]) * h
    last = phi_2 > phi_2[-1] - 2 * math.pi / z2
    means = {k: v[last, 2].mean() for k, v in dte.items()}
    print(f"DTE mean over the last mesh cycle: PMOR-Hertz {means['spur-pmor'] * 1e6:.3f} µm, lumped {means['spur'] * 1e6:.3f} µm")
    assert abs(means["spur"] / means["spur-pmor"] - 1.0) < 0.02
    after = t > 8e-3
    difference = (dte["spur-pmor"][:, 2] - dte["spur"][:, 2])[after]
    power = np.abs(np.fft.rfft(difference - difference.mean())) ** 2
    f = np.fft.rfftfreq(difference.size, h)
    band = power[(f > 2e3) & (f < 4.2e3)].sum() / power[1:].sum()
    print(f"difference after 8 ms: RMS {difference.std() * 1e6:.3f} µm; share of its power at 2–4.2 kHz {band:.3f}")
    assert band > 0.7

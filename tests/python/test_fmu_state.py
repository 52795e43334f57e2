"""FMU state handling through fmpy, compared bit for bit.

Independent evidence: the FMI 2.0 standard's semantics of fmi2GetFMUstate /
fmi2SetFMUstate / fmi2SerializeFMUstate / fmi2DeSerializeFMUstate (a restored
state must continue exactly as the original), plus determinism: the same
instance-local computation on the same inputs must give the same doubles.
Instances in the two-instance test share one extracted shared library, so any
process-global state in the binary would show up as a difference.
Inputs vary every step and so does the step size (the FMU claims
canHandleVariableCommunicationStepSize).
"""

import pytest

N_WARMUP = 40
N_STEPS = 60


def _run(slave, schedule_iter):
    """Apply the schedule; return the outputs after every step and the end time."""
    outputs, t_end = [], None
    for t, h, tau_1, tau_2 in schedule_iter:
        slave.set_inputs(tau_1, tau_2)
        slave.step(t, h)
        outputs.append(slave.outputs())
        t_end = t + h
    return outputs, t_end


def _warm_up(slave, schedule, seed=0.0):
    _, t = _run(slave, schedule(N_WARMUP, seed=seed))
    return t


def test_get_set_state_replays_identically(fmi_case, make_slave, schedule):
    slave = make_slave(fmi_case, "replay")
    t0 = _warm_up(slave, schedule)
    state = slave.fmu.getFMUstate()
    first, _ = _run(slave, schedule(N_STEPS, seed=1.0, t0=t0))
    slave.fmu.setFMUstate(state)
    second, _ = _run(slave, schedule(N_STEPS, seed=1.0, t0=t0))
    slave.fmu.freeFMUstate(state)
    assert first[0] != first[-1], "the run must actually move"
    assert second == first          # tuples of Python floats/ints: exact equality


def test_set_state_twice_and_state_survives_further_steps(fmi_case, make_slave, schedule):
    slave = make_slave(fmi_case, "replay_twice")
    t0 = _warm_up(slave, schedule)
    state = slave.fmu.getFMUstate()
    runs = []
    for _ in range(3):
        slave.fmu.setFMUstate(state)
        runs.append(_run(slave, schedule(N_STEPS, seed=2.0, t0=t0))[0])
    slave.fmu.freeFMUstate(state)
    assert runs[0] == runs[1] == runs[2]


def test_serialized_state_restores_into_fresh_instance(fmi_case, make_slave, schedule):
    original = make_slave(fmi_case, "original")
    t0 = _warm_up(original, schedule)
    state = original.fmu.getFMUstate()
    blob = original.fmu.serializeFMUstate(state)
    original.fmu.freeFMUstate(state)
    assert isinstance(blob, bytes) and len(blob) > 0
    expected, _ = _run(original, schedule(N_STEPS, seed=3.0, t0=t0))

    fresh = make_slave(fmi_case, "fresh")
    restored = fresh.fmu.deSerializeFMUstate(blob)
    fresh.fmu.setFMUstate(restored)
    fresh.fmu.freeFMUstate(restored)
    got, _ = _run(fresh, schedule(N_STEPS, seed=3.0, t0=t0))
    assert got == expected

    # Serializing the restored instance's state again gives the same bytes.
    again = make_slave(fmi_case, "again")
    state_b = again.fmu.deSerializeFMUstate(blob)
    assert again.fmu.serializeFMUstate(state_b) == blob
    again.fmu.freeFMUstate(state_b)


def test_two_instances_are_independent(fmi_case, make_slave, schedule):
    # Solo runs, one instance alive at a time.
    solo_a = make_slave(fmi_case, "solo_a")
    expected_a, _ = _run(solo_a, schedule(N_WARMUP + N_STEPS, seed=0.0))
    solo_a.free()
    solo_b = make_slave(fmi_case, "solo_b")
    expected_b, _ = _run(solo_b, schedule(N_WARMUP + N_STEPS, seed=5.0))
    solo_b.free()

    # Interleaved: both alive in one process, stepping alternately.
    a = make_slave(fmi_case, "inst_a")
    b = make_slave(fmi_case, "inst_b")
    got_a, got_b = [], []
    for step_a, step_b in zip(schedule(N_WARMUP + N_STEPS, seed=0.0), schedule(N_WARMUP + N_STEPS, seed=5.0)):
        got_a += _run(a, [step_a])[0]
        got_b += _run(b, [step_b])[0]

    assert got_a != got_b
    assert got_a == expected_a
    assert got_b == expected_b

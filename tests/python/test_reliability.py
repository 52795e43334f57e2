"""Issue 13, item 1, through fmpy on every FMU kind (lumped spur and helical, PMOR-Hertz spur):
every bad input is answered with the status FMI 2.0.4 asks for, a log line that says why, and an
instance that is usable afterwards.

Independent evidence: FMI 2.0.4 §4.2.3 (a status the slave cannot give is fmi2Discard), §2.1.3
(after fmi2Error the master may resume from a state saved with fmi2GetFMUstate), and the state
format documented in src/fmi2/instance.rs (magic, version, GUID, payload, SHA-256), rebuilt here
in Python with hashlib to forge well-formed states with bad parameters.
"""

import hashlib
import random
import struct
import time

import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (fmi2Discard, fmi2DoStepStatus, fmi2Error, fmi2LastSuccessfulTime,
                       fmi2PendingStatus, fmi2Terminated)

H = 1e-4
# The stated bounds of src/fmu/gear_pair.rs (MAX_SUBSTEPS_LUMPED / MAX_SUBSTEPS_PMOR).
MAX_SUBSTEPS = {"lumped": 4e7, "pmor-hertz": 1e5}


def _drive(slave, t0, n):
    """n steps of H, 185 N·m against a viscous load; returns the end time."""
    t = t0
    for _ in range(n):
        slave.set_inputs(185.0, -20.0 * slave.fmu.getReal([slave.vr["w_2"]])[0])
        slave.step(t, H)
        t += H
    return t


def _refused(call, status):
    with pytest.raises(FMICallException) as excinfo:
        call()
    assert excinfo.value.status == status, f"expected status {status}, got {excinfo.value.status}"


def _new_lines(log_capture, name, since):
    return log_capture.for_instance(name)[since:]


def _assert_logged(log_capture, name, since, status, *needles):
    lines = _new_lines(log_capture, name, since)
    hits = [m for (s, _, m) in lines if s == status and all(n in m for n in needles)]
    assert hits, f"no log line with status {status} containing {needles}: {lines}"


def test_status_queries_without_an_answer_are_discarded(fmi_case, make_slave, log_capture):
    name = f"status_{fmi_case.name}"
    # Logging off: a discard is still reported with its reason.
    slave = make_slave(fmi_case, name, callbacks=log_capture.callbacks, logging_on=False)
    t = _drive(slave, 0.0, 2)
    fmu = slave.fmu
    queries = [
        (fmu.getStatus, "fmi2GetStatus", fmi2DoStepStatus, "steps are synchronous"),
        (fmu.getStatus, "fmi2GetStatus", fmi2LastSuccessfulTime, "it is a Real status"),
        (fmu.getStringStatus, "fmi2GetStringStatus", fmi2PendingStatus, "steps are synchronous"),
        (fmu.getIntegerStatus, "fmi2GetIntegerStatus", fmi2Terminated, "it is a Boolean status"),
        (fmu.getRealStatus, "fmi2GetRealStatus", fmi2DoStepStatus, "steps are synchronous"),
        (fmu.getBooleanStatus, "fmi2GetBooleanStatus", fmi2PendingStatus, "steps are synchronous"),
        (fmu.getBooleanStatus, "fmi2GetBooleanStatus", 42, "not an fmi2StatusKind"),
    ]
    for query, function, kind, why in queries:
        since = len(log_capture.for_instance(name))
        _refused(lambda: query(kind), fmi2Discard)
        _assert_logged(log_capture, name, since, fmi2Discard, function, "cannot be given", why)
        t = _drive(slave, t, 1)  # still usable: the phase did not change
    assert fmu.getRealStatus(fmi2LastSuccessfulTime) == t
    assert fmu.getBooleanStatus(fmi2Terminated) is False


def test_a_step_needing_unbounded_work_is_refused_at_once(fmi_case, make_slave, log_capture):
    name = f"bound_{fmi_case.name}"
    slave = make_slave(fmi_case, name, callbacks=log_capture.callbacks, logging_on=True)
    t = _drive(slave, 0.0, 3)
    saved = slave.fmu.getFMUstate()
    max_step = slave.fmu.getReal([slave.vr["max_step"]])[0]
    bound = MAX_SUBSTEPS[fmi_case.kind]
    for h in (1e9, (bound + 1) * max_step):
        since = len(log_capture.for_instance(name))
        started = time.perf_counter()
        _refused(lambda: slave.step(t, h), fmi2Error)
        assert time.perf_counter() - started < 0.5, "refused before any work"
        _assert_logged(log_capture, name, since, fmi2Error, "fmi2DoStep", "communicationStepSize h = ",
                       "with max_step = ", "sub-steps, more than the bound of", "per call")
        slave.fmu.setFMUstate(saved)
        t_after = _drive(slave, t, 2)  # usable again from the saved state
        assert t_after > t
        slave.fmu.setFMUstate(saved)
    slave.fmu.freeFMUstate(saved)
    # max_step that is not a positive normal number is refused at fmi2SetReal.
    for bad in (0.0, -1e-5, 1e-310):
        fmu = slave.fmu
        fmu.reset()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        since = len(log_capture.for_instance(name))
        _refused(lambda: fmu.setReal([slave.vr["max_step"]], [bad]), fmi2Error)
        _assert_logged(log_capture, name, since, fmi2Error,
                       "max_step must be a finite, positive, normal number of seconds")
    fmu.reset()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    assert _drive(slave, 0.0, 2) > 0.0


def test_time_check_scales_with_the_step_not_with_t(fmi_case, make_slave, log_capture):
    name = f"time_{fmi_case.name}"
    t0 = 1e9
    slave = make_slave(fmi_case, name, callbacks=log_capture.callbacks, logging_on=True, start_time=t0)
    saved = slave.fmu.getFMUstate()
    for off in (1.0, -1.0, 1e-5):
        since = len(log_capture.for_instance(name))
        _refused(lambda: slave.step(t0 + off, H), fmi2Error)
        _assert_logged(log_capture, name, since, fmi2Error, "currentCommunicationPoint",
                       "is not the FMU's time 1000000000")
        slave.fmu.setFMUstate(saved)
    # The master's grid t0 + k·H is accepted.
    for k in range(20):
        slave.set_inputs(185.0, -185.0 * 31 / 21)
        slave.step(t0 + k * H, H)
    assert abs(slave.fmu.getRealStatus(fmi2LastSuccessfulTime) - (t0 + 20 * H)) < 1e-6
    slave.fmu.freeFMUstate(saved)


def _split(blob):
    """(guid, payload) of a serialized state, checking the documented layout."""
    assert blob[:8] == b"GFMUSTAT"
    assert struct.unpack_from("<I", blob, 8)[0] == 2
    n = struct.unpack_from("<I", blob, 12)[0]
    guid = blob[16:16 + n]
    m = struct.unpack_from("<Q", blob, 16 + n)[0]
    payload = blob[24 + n:24 + n + m]
    assert len(blob) == 24 + n + m + 32
    assert blob[24 + n + m:] == hashlib.sha256(blob[:24 + n + m]).digest()
    return guid, payload


def _forge(guid, payload):
    body = b"GFMUSTAT" + struct.pack("<I", 2) + struct.pack("<I", len(guid)) + guid
    body += struct.pack("<Q", len(payload)) + payload
    return body + hashlib.sha256(body).digest()


def test_serialized_state_refuses_flips_trailing_bytes_and_other_fmus(fmi_case, gear_fmus, make_slave,
                                                                      log_capture):
    name = f"flips_{fmi_case.name}"
    slave = make_slave(fmi_case, name, callbacks=log_capture.callbacks, logging_on=True)
    t = _drive(slave, 0.0, 5)
    good = slave.fmu.getFMUstate()
    blob = slave.fmu.serializeFMUstate(good)
    _split(blob)
    outputs = slave.outputs()
    rng = random.Random(13)
    bits = rng.sample(range(len(blob) * 8), 300)
    for bit in bits:
        flipped = bytearray(blob)
        flipped[bit // 8] ^= 1 << (bit % 8)
        since = len(log_capture.for_instance(name))
        _refused(lambda: slave.fmu.deSerializeFMUstate(bytes(flipped)), fmi2Error)
        lines = _new_lines(log_capture, name, since)
        assert any(s == fmi2Error and "fmi2DeSerializeFMUstate: serialized FMU state" in m for s, _, m in lines), \
            f"bit {bit}: {lines}"
    since = len(log_capture.for_instance(name))
    _refused(lambda: slave.fmu.deSerializeFMUstate(blob + b"\0"), fmi2Error)
    _assert_logged(log_capture, name, since, fmi2Error, "trailing bytes after its checksum")
    # A state of another FMU (another GUID): the helical pair's into the spur, the spur's into
    # the others.
    other_case = gear_fmus["helical" if fmi_case.name != "helical" else "spur"]
    other = make_slave(other_case, f"other_{fmi_case.name}")
    _drive(other, 0.0, 5)
    other_state = other.fmu.getFMUstate()
    other_blob = other.fmu.serializeFMUstate(other_state)
    other.fmu.freeFMUstate(other_state)
    since = len(log_capture.for_instance(name))
    _refused(lambda: slave.fmu.deSerializeFMUstate(other_blob), fmi2Error)
    _assert_logged(log_capture, name, since, fmi2Error, "serialized FMU state is from another FMU: GUID")
    # Nothing changed; a good state brings the instance back and it steps on.
    assert slave.outputs() == outputs
    slave.fmu.setFMUstate(slave.fmu.deSerializeFMUstate(blob))
    assert _drive(slave, t, 2) > t
    slave.fmu.freeFMUstate(good)


@pytest.mark.parametrize("parameter, bad, reason", [
    ("inertia_1", -1.0, "inertia_1 must be > 0, got -1"),
    ("max_step", 0.0, "max_step must be a finite, positive, normal number of seconds, got 0e0"),
    ("mesh_damping_ratio", 1.5, "mesh_damping_ratio must be in [0, 1), got 1.5"),
])
def test_restored_parameters_are_revalidated(fmi_case, make_slave, log_capture, parameter, bad, reason):
    name = f"revalidate_{fmi_case.name}_{parameter}"
    # A value found once in the payload: the PMOR-Hertz FMU's default mesh_damping_ratio is 0,
    # whose eight zero bytes occur all over it.
    parameters = {"mesh_damping_ratio": 0.0123} if parameter == "mesh_damping_ratio" else None
    slave = make_slave(fmi_case, name, callbacks=log_capture.callbacks, logging_on=True, parameters=parameters)
    t = _drive(slave, 0.0, 5)
    good = slave.fmu.getFMUstate()
    blob = slave.fmu.serializeFMUstate(good)
    guid, payload = _split(blob)
    value = struct.pack("<d", slave.fmu.getReal([slave.vr[parameter]])[0])
    assert payload.count(value) == 1, f"{parameter}'s value must occur once in the payload"
    forged = _forge(guid, payload.replace(value, struct.pack("<d", bad)))
    outputs = slave.outputs()
    since = len(log_capture.for_instance(name))
    _refused(lambda: slave.fmu.deSerializeFMUstate(forged), fmi2Error)
    _assert_logged(log_capture, name, since, fmi2Error,
                   "fmi2DeSerializeFMUstate: the FMU state is refused: " + reason)
    assert slave.outputs() == outputs, "the instance keeps its state"
    # The forge itself is sound: the unchanged payload re-packed is accepted.
    restored = slave.fmu.deSerializeFMUstate(_forge(guid, payload))
    slave.fmu.setFMUstate(restored)
    assert _drive(slave, t, 2) > t
    slave.fmu.freeFMUstate(restored)
    slave.fmu.freeFMUstate(good)

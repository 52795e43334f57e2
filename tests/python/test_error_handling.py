"""A NaN input is rejected, reported through the logger, and recoverable.

Independent evidence: the FMI 2.0 standard (section 2.1.3): fmi2Error means
the step/call cannot be honoured; the FMU must report why through the logger
callback; a simulation may then be resumed from an FMU state taken earlier
with fmi2SetFMUstate.  What actually reaches Python is checked through fmpy's
native logging proxy, which expands the FMU's "%s" format with its variadic
argument (plain ctypes would only ever see the literal "%s").
"""

import math

import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2Error

N_WARMUP = 30
N_STEPS = 40


def _run(slave, schedule_iter):
    outputs = []
    for t, h, tau_1, tau_2 in schedule_iter:
        slave.set_inputs(tau_1, tau_2)
        slave.step(t, h)
        outputs.append(slave.outputs())
    return outputs


def _end_time(schedule_iter):
    t = 0.0
    for t, h, _, _ in schedule_iter:
        pass
    return t + h


def test_logger_proxy_delivers_formatted_text(log_capture):
    # Self-check of the capture path, independent of the FMU: call the proxied
    # logger from C through ctypes with a "%s" format and one vararg.
    import ctypes
    proxy = ctypes.cast(log_capture.callbacks.logger, ctypes.c_void_p).value
    c_logger = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int,
                                ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p)(proxy)
    c_logger(None, b"selfcheck", 0, b"logAll", b"%s", b"hello from a vararg")
    assert ("selfcheck", 0, "logAll", "hello from a vararg") in log_capture.records


@pytest.mark.parametrize("input_name", ["tau_1", "tau_2"])
def test_nan_input_is_rejected_logged_and_recoverable(fmi_case, make_slave, schedule, log_capture, input_name):
    name = f"nan_{fmi_case.name}_{input_name}"
    slave = make_slave(fmi_case, name, callbacks=log_capture.callbacks, logging_on=True)
    _run(slave, schedule(N_WARMUP))
    t0 = _end_time(schedule(N_WARMUP))
    state = slave.fmu.getFMUstate()
    uninterrupted = _run(slave, schedule(N_STEPS, seed=1.0, t0=t0))

    n_before = len(log_capture.for_instance(name))
    with pytest.raises(FMICallException) as excinfo:
        slave.fmu.setReal([slave.vr[input_name]], [math.nan])
    assert excinfo.value.function == "fmi2SetReal"
    assert excinfo.value.status == fmi2Error

    new_lines = log_capture.for_instance(name)[n_before:]
    assert new_lines, "fmi2Error without any log message"
    error_lines = [(s, c, m) for (s, c, m) in new_lines if s >= fmi2Error]
    assert error_lines, f"no log line with status >= fmi2Error: {new_lines}"
    texts = " | ".join(m for _, _, m in error_lines)
    assert "%s" not in texts, f"unformatted message reached the logger: {texts!r}"
    assert ("nan" in texts.lower() or "finite" in texts.lower()), f"message does not name the problem: {texts!r}"

    # Resume from the state taken before the error: identical to the uninterrupted run.
    slave.fmu.setFMUstate(state)
    slave.fmu.freeFMUstate(state)
    resumed = _run(slave, schedule(N_STEPS, seed=1.0, t0=t0))
    assert resumed == uninterrupted

"""Static checks of the packaged FMUs.

Independent evidence: fmpy's validator checks modelDescription.xml against the
FMI 2.0 XSD schema and fmpy's own rules (variable names, ModelStructure
completeness, causality/variability/initial combinations, start values, units).
It knows nothing about gearfmu.  The remaining assertions compare the model
description with the interface contract the FMU promises.
"""

import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu


def test_validate_fmu_reports_no_problems(fmi_case):
    problems = validate_fmu(str(fmi_case.fmu_path))
    assert problems == [], f"{fmi_case.fmu_path.name}: {problems}"


def test_model_description_matches_contract(fmi_case):
    model = read_model_description(str(fmi_case.fmu_path), validate=False)
    assert model.fmiVersion == "2.0"
    cs = model.coSimulation
    assert cs is not None and cs.modelIdentifier == "gearfmu"
    assert cs.canHandleVariableCommunicationStepSize
    assert cs.canGetAndSetFMUstate
    assert cs.canSerializeFMUstate

    variables = {v.name: v for v in model.modelVariables}
    expected = {
        "tau_1": ("input", "Real"), "tau_2": ("input", "Real"),
        "phi_1": ("output", "Real"), "phi_2": ("output", "Real"),
        "w_1": ("output", "Real"), "w_2": ("output", "Real"),
        "dte": ("output", "Real"), "dte_angle": ("output", "Real"),
        "mesh_force": ("output", "Real"), "mesh_stiffness": ("output", "Real"),
        "contact_pairs": ("output", "Integer"),
        "phi_1_start": ("parameter", "Real"), "phi_2_start": ("parameter", "Real"),
        "w_1_start": ("parameter", "Real"), "w_2_start": ("parameter", "Real"),
        "max_step": ("parameter", "Real"), "inertia_1": ("parameter", "Real"),
        "inertia_2": ("parameter", "Real"), "mesh_damping_ratio": ("parameter", "Real"),
        "friction_coefficient": ("parameter", "Real"),
        "force_tangential": ("output", "Real"), "force_radial": ("output", "Real"),
        "force_axial": ("output", "Real"), "mesh_power_loss": ("output", "Real"),
        "mesh_efficiency": ("output", "Real"), "mesh_energy_loss": ("output", "Real"),
        "friction_regularization": ("output", "Real"),
        "oil_viscosity": ("parameter", "Real"), "flank_roughness_ra": ("parameter", "Real"),
        "lubricant_factor": ("parameter", "Real"), "friction_coefficient_applied": ("output", "Real"),
    }
    for name, (causality, type_) in expected.items():
        assert name in variables, f"missing variable {name}"
        assert variables[name].causality == causality, name
        assert variables[name].type == type_, name
    for name in ("tau_1", "tau_2"):
        assert float(variables[name].start) == 0.0
    # Per model kind: the lumped RK4 bound; the PMOR-Hertz model's own, 0.6 × its integrator's
    # stability limit on the linearized pair (velocity Verlet: 20 µs for the default spur pair),
    # so only its range is fixed here: at least 5 µs (the step set by the retained physics, not
    # by the 57 kHz hub mode or the body modes above the cut-off), at most 0.6 × Verlet's 2/ω of
    # the retained mesh mode (3.0–3.8 kHz here: below 50 µs).
    if fmi_case.kind == "lumped":
        assert float(variables["max_step"].start) == pytest.approx(1e-5)
    else:
        assert 5e-6 <= float(variables["max_step"].start) <= 5e-5
    # The spec's mounting.mesh_damping_ratio (0.05 in the Kurokawa specs) reaches both models.
    assert float(variables["mesh_damping_ratio"].start) == pytest.approx(0.05)
    # "default from geometry": the inertia start values are what inspect reports (the exact
    # profile integral); the PMOR-Hertz FMU takes its gears' inertia from the FE mass, which
    # must agree with that integral to the mesh's discretization (0.1 %).
    rel = 1e-9 if fmi_case.kind == "lumped" else 1e-3
    assert float(variables["inertia_1"].start) == pytest.approx(fmi_case.mesh["inertia_1_kgm2"], rel=rel)
    assert float(variables["inertia_2"].start) == pytest.approx(fmi_case.mesh["inertia_2_kgm2"], rel=rel)

"""The contact pattern through the command line (issue 27): `fmu-build ste --csv` on the spur pair
misaligned by 20 µm, read by scripts/contact_pattern.py. The spec says a positive
`mounting.misalignment_um` closes the +z face end; the load per face width, averaged over the mesh
cycle, must then rise section by section from −z to +z (the sign convention, end to end), and
the PNG must be written."""

from __future__ import annotations

import importlib.util
import sys

from conftest import REPO_ROOT, _fmu_build


def _pattern_module():
    spec = importlib.util.spec_from_file_location("contact_pattern", REPO_ROOT / "scripts" / "contact_pattern.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("contact_pattern", module)
    spec.loader.exec_module(module)
    return module


def test_misalignment_loads_the_closing_face_end(tmp_path):
    text = (REPO_ROOT / "examples" / "kurokawa_spur.toml").read_text()
    spec = tmp_path / "misaligned.toml"
    spec.write_text(text.replace("[mounting]\n", "[mounting]\nmisalignment_um = 20.0\n", 1))
    csv_path, png = tmp_path / "ste.csv", tmp_path / "pattern.png"
    _fmu_build("ste", str(spec), "--torque-nm", "185", "--angles", "12", "--csv", str(csv_path))
    pattern = _pattern_module()
    angles, loads = pattern.read_pattern(csv_path)[185.0]
    means = pattern.section_means(loads)
    print("section means (N/mm, -z to +z):", [round(m, 1) for m in means])
    assert len(angles) == 12 and len(means) >= 3
    assert all(a < b for a, b in zip(means, means[1:])), means
    assert pattern.main([str(csv_path), "--face-width-mm", "15", "--png", str(png)]) == 0
    assert png.stat().st_size > 10_000

"""`artibus check VEHICLE.ssv`: the project's vehicle sets pass; each planted
mistake is reported, naming the file, the parameter and its value, and the
command exits with 1."""
import re
import subprocess
import sys

import pytest

from artibus import ROOT
from artibus.bench import check

PARAMS = ROOT / "ssp" / "parameters"
TEMPLATE = PARAMS / "Template.ssv"


@pytest.mark.parametrize("name", ["Template", "Bus36m", "Scania18m", "Scania18mHeavyRear", "Urbino18",
                                  "Urbino18Dynamics"])
def test_known_good_sets_pass(name):
    model, probs = check.check_file(PARAMS / f"{name}.ssv")
    assert model in ("BusDynamics", "BusKinematics")
    assert probs == [], [p.text(name) for p in probs]


def _set(text, name, value, kind="Real"):
    """The template with one parameter's value replaced (or added when absent)."""
    pat = re.compile(rf'(<ssv:Parameter name="{re.escape(name)}"><ssv:{kind} value=")[^"]*(")')
    if pat.search(text):
        return pat.sub(lambda m: m.group(1) + str(value) + m.group(2), text)
    line = f'    <ssv:Parameter name="{name}"><ssv:{kind} value="{value}"/></ssv:Parameter>\n'
    return text.replace("  </ssv:Parameters>", line + "  </ssv:Parameters>")


def _problems(tmp_path, edits):
    text = TEMPLATE.read_text()
    for name, value, kind in edits:
        text = _set(text, name, value, kind)
    path = tmp_path / "Planted.ssv"
    path.write_text(text)
    _, probs = check.check_file(path)
    return path, [p.text(path) for p in probs]


# the template's numbers (Scania 18 m): lFront[1] 4.644, lRear[1] 5.128, lFront[2] 4.777,
# m[1] 8100 kg over a 9.772 m body
PLANTED = {
    "axle beyond the body's front": ([("xA[1]", 6.0, "Real")], "xA[1] = 6", "outside module 1's body"),
    "negative mass": ([("m[2]", -100.0, "Real")], "m[2] = -100", "positive"),
    "hinge far behind the body": ([("lHf[1]", 8.0, "Real")], "lHf[1] = 8", "behind the rear"),
    "hinge ahead of the rear module's centre of mass": ([("lHr[1]", -1.0, "Real")], "lHr[1] = -1", "> 0"),
    # J/(m L^2) = 5000 / (8100 * 9.772^2) = 0.0065, far below 1/20
    "inertia too small": ([("Jz[1]", 5000.0, "Real")], "Jz[1] = 5000", "implausible"),
    # 2.0e6 / (8100 * 9.772^2) = 2.59, far above 1/8
    "inertia too large": ([("Jz[1]", 2.0e6, "Real")], "Jz[1] = 2e+06", "implausible"),
    "more axles than entries": ([("nAxles", 4, "Integer")], "xA[4]", "missing"),
    "entry beyond the modules": ([("m[3]", 8000.0, "Real")], "m[3] = 8000", "beyond the 2 modules"),
    "axle on a module that does not exist": ([("axleModule[3]", 3, "Integer")], "axleModule[3] = 3",
                                             "no such module"),
    "misspelt name": ([("Jzz[1]", 1.0, "Real")], "Jzz[1] = 1", "did you mean Jz[1]"),
    # module 2 rests on A3 and hinge 1 (4.777 m ahead of its centre of mass): with A3 2 m ahead too,
    # F3 + H = m2 g and 2 F3 + 4.777 H = 0 give H = -0.72 m2 g: the hinge pulls module 1's tail
    # up by more than module 1 weighs behind its front axle, and A2's load goes negative
    "centre of mass outside the supports": ([("xA[3]", 2.0, "Real")], "static load of axle 2", "negative"),
    "zero cornering stiffness": ([("C[2]", 0.0, "Real")], "C[2] = 0", "positive"),
    "static load missing without masses": ([("FzFromMasses", "false", "Boolean")], "Fz0[1]", "static axle load"),
}


@pytest.mark.parametrize("case", list(PLANTED))
def test_planted_mistake_is_reported(tmp_path, case):
    edits, where, what = PLANTED[case]
    path, lines = _problems(tmp_path, edits)
    hits = [ln for ln in lines if where in ln and what in ln]
    assert hits, f"{case}: expected '{where}' ... '{what}' in {lines}"
    assert all(ln.startswith(str(path)) for ln in lines)


def test_kinematic_set_mistakes(tmp_path):
    text = (PARAMS / "Urbino18.ssv").read_text()
    text = _set(text, "L[1]", 0.0)
    text = _set(text, "L[2]", 3.0)          # a second wagon's length while N = 1
    path = tmp_path / "Kin.ssv"
    path.write_text(text)
    model, probs = check.check_file(path)
    lines = [p.text(path) for p in probs]
    assert model == "BusKinematics"
    assert any("L[1] = 0" in ln and "positive" in ln for ln in lines), lines
    assert any("L[2] = 3" in ln and "beyond" in ln for ln in lines), lines


def test_cli_exit_status_and_message(tmp_path):
    path, _ = _problems(tmp_path, [("xA[2]", -7.0, "Real")])     # lRear[1] = 5.128
    r = subprocess.run([sys.executable, "-m", "artibus", "check", str(path)], capture_output=True, text=True)
    assert r.returncode == 1, r.stdout + r.stderr
    assert f"{path}: xA[2] = -7: axle 2 lies outside module 1's body" in r.stdout
    r = subprocess.run([sys.executable, "-m", "artibus", "check", str(TEMPLATE), "Urbino18"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "consistent" in r.stdout

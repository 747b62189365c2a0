"""A bench's variants: parameter sets of one bench (variants/<name>.ssv in the
bench folder, packed into the .ssp), selected by name, applied after the
bench's bindings and before the user's values; checked through
BusKinematics' eq. 19 (kappa0 = tan(gammaF) / L0) on a two-FMU bench."""
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from artibus import ArtibusError
from artibus.bench import ssp
from artibus.runner import run
from test_runner import LEAD_FOLLOW, QUIET, make_ssp


def variant(name, **values):
    rows = "".join(f'<ssv:Parameter name="{k}"><ssv:Real value="{v}"/></ssv:Parameter>' for k, v in values.items())
    return ('<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet '
            'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" '
            f'version="1.0" name="{name}"><ssv:Parameters>{rows}</ssv:Parameters></ssv:ParameterSet>')


def bench_with_variants(tmp_path, files):
    path = make_ssp(tmp_path, **LEAD_FOLLOW)
    with zipfile.ZipFile(path, "a") as z:
        for name, text in files.items():
            z.writestr(f"variants/{name}.ssv", text)
    return path


def test_variants_are_listed_applied_in_order_and_yield_to_the_user(tmp_path):
    path = bench_with_variants(tmp_path, {"short": variant("short", **{"Follow.L0": 4.0}),
                                          "shorter": variant("shorter", **{"Follow.L0": 2.5})})
    assert ssp.variants(path) == ["short", "shorter"]
    assert ssp.variant_overrides(path, ["short"]) == {"Follow.L0": 4.0}
    assert ssp.variant_overrides(path, ["short", "shorter"]) == {"Follow.L0": 2.5}   # later wins
    for names, L0 in ((["short"], 4.0), (["shorter", "short"], 4.0), (["short", "shorter"], 2.5)):
        r = run(path, step=0.05, overrides={**ssp.variant_overrides(path, names), **QUIET})
        assert np.max(np.abs(r["Lead.beta[1]"])) > 0.05
        np.testing.assert_allclose(r["Follow.kappa[0]"], np.tan(2.0 * r["Lead.beta[1]"] + 0.01) / L0, rtol=1e-12)
    # the user's --set wins over a variant: the CLI merges them in that order
    out = tmp_path / "r.csv"
    subprocess.run([sys.executable, "-m", "artibus", "run", str(path), "--variant", "short",
                    "--set", "Follow.L0=3.0", "--set", "Follow.testSteerAmp=0", "--step", "0.05",
                    "--record", "Lead.beta[1]", "--record", "Follow.kappa[0]", "-o", str(out)],
                   check=True, capture_output=True)
    d = np.genfromtxt(out, delimiter=",", names=True)
    beta, kappa = d[d.dtype.names[1]], d[d.dtype.names[2]]
    np.testing.assert_allclose(kappa, np.tan(2.0 * beta + 0.01) / 3.0, rtol=1e-9)


@pytest.mark.parametrize("files, names, words", [
    ({"short": variant("short", **{"Follow.L0": 4.0})}, ["long"], ["--variant long", "known: short"]),
    ({}, ["short"], ["--variant short", "known: none"]),
    ({"bad": variant("bad", L0=4.0)}, ["bad"], ["variants/bad.ssv", "'L0'", "Component.variable"]),
    ({"broken": "<ssv:ParameterSet"}, ["broken"], ["variants/broken.ssv", "not a valid SSP parameter-value file"]),
])
def test_bad_variants_are_errors_naming_the_file_and_the_name(tmp_path, files, names, words):
    path = bench_with_variants(tmp_path, files)
    with pytest.raises(ArtibusError) as e:
        ssp.variant_overrides(path, names)
    assert all(w in str(e.value) for w in words), str(e.value)


def test_a_variant_naming_no_parameter_of_the_component_is_an_error(tmp_path):
    path = bench_with_variants(tmp_path, {"typo": variant("typo", **{"Follow.Lzero": 4.0})})
    with pytest.raises(ArtibusError) as e:
        run(path, step=0.05, overrides=ssp.variant_overrides(path, ["typo"]))
    assert "Lzero" in str(e.value)


def test_the_bench_folders_variants_are_packed(tmp_path):
    """Every variants/*.ssv of a bench folder goes into its .ssp."""
    for bench in ssp.bench_names():
        folder = ssp.BENCH_DIR / bench / ssp.VARIANT_DIR
        expected = sorted(p.stem for p in folder.glob("*.ssv"))
        if expected:
            assert ssp.variants(ssp.pack(bench, out_dir=tmp_path)) == expected


def test_heavy_rear_rebinds_the_vehicle_for_plant_and_controller():
    """Scania18m_Damping's heavyRear variant binds Scania18mHeavyRear.ssv
    where the bench binds Scania18m.ssv: the plant gets Table 5.4's values,
    the controller its m2, f2, b2 through the same mapping; nothing else
    changes, and variants named before it keep their values."""
    o = ssp.variant_overrides("Scania18m_Damping", ["option1", "heavyRear"])
    assert o["Controller.option"] == "angleError"     # option 1: the variant names its item (ssv:Enumeration)
    assert o["Bus.m[2]"] == 10131.0 and o["Bus.lHr[1]"] == 5.107 and o["Bus.xA[3]"] == 0.167
    assert o["Controller.m2"] == 10131.0 and o["Controller.f2"] == 5.107 and o["Controller.b2"] == -0.167
    assert o["Bus.FzFromMasses"] is False
    assert o["Bus.Fz0[3]"] == pytest.approx(10131.0 * 9.81)
    assert not any(k.startswith(("Driver.", "Damper.", "Baseline.")) for k in o)


def test_heavy_rear_set_is_scania18m_but_for_table_5_4():
    """One source of truth: Scania18mHeavyRear.ssv repeats Scania18m.ssv but
    for the values Table 5.4 changes (and the given static loads)."""
    from artibus.bench.parameters import read_parameters
    base, heavy = read_parameters("Scania18m"), read_parameters("Scania18mHeavyRear")
    changed = {k for k in set(base) | set(heavy) if base.get(k) != heavy.get(k)}
    assert changed == {"m[2]", "lHr[1]", "xA[3]", "FzFromMasses", "Fz0[1]", "Fz0[2]", "Fz0[3]"}
    assert heavy["lHr[1]"] - heavy["xA[3]"] == pytest.approx(base["lHr[1]"] - base["xA[3]"], abs=1e-3)  # l2 kept


def test_rebinding_a_set_the_bench_does_not_bind_is_an_error(tmp_path):
    rebind = ('<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet '
              'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" '
              'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0" name="r">'
              '<ssv:Parameters/><ssv:Annotations><ssc:Annotation type="org.artibus.variant">'
              '<Variant xmlns="urn:artibus"><Rebind from="resources/{a}" to="resources/{b}"/></Variant>'
              '</ssc:Annotation></ssv:Annotations></ssv:ParameterSet>')
    path = bench_with_variants(tmp_path, {"r": rebind.format(a="nothing.ssv", b="x.ssv")})
    with pytest.raises(ArtibusError) as e:
        ssp.variant_overrides(path, ["r"])
    assert "variants/r.ssv" in str(e.value) and "x.ssv" in str(e.value)
    with zipfile.ZipFile(path, "a") as z:
        z.writestr("resources/x.ssv", variant("x"))
    with pytest.raises(ArtibusError) as e:
        ssp.variant_overrides(path, ["r"])
    assert "nothing.ssv" in str(e.value) and "binds no such parameter set" in str(e.value)


def _with_stop(name, stop):
    return ('<?xml version="1.0" encoding="UTF-8"?><ssv:ParameterSet '
            'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" '
            'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
            f'version="1.0" name="{name}"><ssv:Parameters/><ssv:Annotations>'
            '<ssc:Annotation type="org.artibus.variant">'
            f'<Variant xmlns="urn:artibus" stopTime="{stop}"/></ssc:Annotation></ssv:Annotations></ssv:ParameterSet>')


def test_a_variant_gives_its_stop_time_and_the_user_overrides_it(tmp_path):
    path = bench_with_variants(tmp_path, {"short": _with_stop("short", 2.0), "bad": _with_stop("bad", -1),
                                          "plain": variant("plain")})
    assert ssp.variant_stop_time(path, ["short"]) == 2.0
    assert ssp.variant_stop_time(path, ["plain"]) is None
    assert ssp.variant_stop_time(path, ["short", "plain"]) == 2.0      # the last that gives one
    with pytest.raises(ArtibusError) as e:
        ssp.variant_stop_time(path, ["bad"])
    assert "variants/bad.ssv" in str(e.value) and "stopTime" in str(e.value)
    for extra, last in (([], 2.0), (["--stop-time", "1.5"], 1.5)):
        out = tmp_path / "r.csv"
        subprocess.run([sys.executable, "-m", "artibus", "run", str(path), "--variant", "short", "--step", "0.05",
                        "--set", "Follow.testSteerAmp=0", "--record", "Lead.beta[1]", "-o", str(out), *extra],
                       check=True, capture_output=True)
        d = np.genfromtxt(out, delimiter=",", names=True)
        assert d["time"][-1] == pytest.approx(last)

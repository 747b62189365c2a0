"""A bench's variants: parameter sets of one bench (variants/<name>.ssv in the
bench folder, packed into the .ssp), selected by name, applied after the
bench's bindings and before the user's values; checked through
BusKinematics' eq. 19 (kappa0 = tan(gammaF) / L0) on a two-FMU bench."""
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from artibus import ArtibusError, ssp
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

"""Exact directional derivatives of the plants (issue 43): fmi2GetDirectionalDerivative and
fmi3GetDirectionalDerivative of MultiAxle3DOF, BusDynamics, BusKinematics and ArticulationDamper,
Model Exchange and Co-Simulation.

Everything here is derived from the FMU through FMPy's plain calls, independently of artibus:

- at random states and inputs (within the ranges below, a few seeds), the Jacobian of the
  state derivatives and outputs (the unknowns) with respect to the continuous states and the
  Real inputs (the knowns, FMI 3.0 2.2.11 / FMI 2.0.4 2.1.9) from the FMU's directional
  derivatives, one unit seed per known, equals the central finite differences of the same FMU
  (Richardson-extrapolated, step h_j = 1e-4 max(1, |v_j|)) to 1e-6 relative: for every unknown
  i, |J_ij - D_ij| s_j <= 1e-6 max_k |D_ik| s_k + 1e-12, s_j = max(1, |v_j|), i.e. each entry's
  error in the change of unknown i that a relative change of known j makes, against the largest
  such change of that unknown (the rows mix units, so a row is its own scale);
- the <ModelStructure> dependencies are exact: with every axle present and steerable, an
  unknown's finite-difference sensitivities are nonzero at some of the random points exactly
  where it declares a dependency (a state or an input), and zero where it does not;
- the derivatives the FMU says it has: providesDirectionalDerivative(s)="true" in FMI 2.0 and
  3.0, ME and CS; fmi3GetAdjointDerivative gives J^T seed.
"""
import ctypes
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave
from lxml import etree

from conftest import fmu3, fmu_file

RTOL = 1e-6
SEEDS = (1, 2, 3)

#: (lo, hi) of the random states and inputs, by name; the plant's parameters at their defaults
#: unless set in PARAMETERS (the largest configuration: every axle present and steerable)
RANGES = {
    "MultiAxle3DOF": {"w_r": (-0.3, 0.3), "v": (-1.0, 1.0), "p": (-0.2, 0.2), "phi": (-0.05, 0.05),
                      "psi": (-3.0, 3.0), "x": (-100.0, 100.0), "y": (-100.0, 100.0),
                      "u": (5.0, 30.0), "delta": (-0.1, 0.1), "M_d": (-2e4, 2e4)},
    "ArticulationDamper": {"pValve": (1e6, 2e7), "Ediss": (0.0, 1e5), "Lambda": (-0.8, 0.8),
                           "LambdaDot": (-0.03, 0.03), "pct": (5.0, 45.0)},     # |Ldot| < 2 v0: tanh not flat
    "BusKinematics": {"thetaj": (-3.0, 3.0), "xj": (-100.0, 100.0), "yj": (-100.0, 100.0),
                      "beta": (-0.3, 0.3), "gammaF": (-0.2, 0.2), "gamma": (-0.1, 0.1), "v": (2.0, 15.0),
                      "omegaMeas": (-0.3, 0.3)},
    "BusDynamics": {"z[1]": (-100.0, 100.0), "z[2]": (-100.0, 100.0), "z[3]": (-3.0, 3.0),
                    "z[4]": (-0.3, 0.3), "z[5]": (-0.3, 0.3), "z[6]": (-0.3, 0.3),
                    "zd[1]": (5.0, 15.0), "zd[2]": (-1.0, 1.0), "zd[3]": (-0.2, 0.2),
                    "zd[4]": (-0.2, 0.2), "zd[5]": (-0.2, 0.2), "zd[6]": (-0.2, 0.2),
                    "delta": (-0.1, 0.1), "Fx": (-2000.0, 2000.0), "Mjoint": (-5000.0, 5000.0)},
}
PARAMETERS = {
    "MultiAxle3DOF": {"n": 6, **{f"steerable[{i}]": True for i in range(1, 7)},
                      **{f"l[{i}]": 3.0 - 1.2 * i for i in range(4, 7)},
                      **{f"k[{i}]": -3e5 for i in range(4, 7)},
                      **{f"d[{i}]": 0.05 * i for i in range(1, 7)}},
    "BusDynamics": {"nModules": 4, "nAxles": 8, "FzFromMasses": False,
                    **{f"Fz0[{a}]": 40000.0 for a in range(1, 9)}},
    "BusKinematics": {"N": 4, **{f"steerable[{i}]": True for i in range(1, 5)}, "j": 2, "k": 3},
    "ArticulationDamper": {"tauP": 0.05},
}
#: dependencies through a switch only (a piecewise constant function: its derivative is 0 where
#: it exists): declared (an importer sorting its equations needs them), zero in any Jacobian
SWITCHES = {"ArticulationDamper": {("Mmax", "LambdaDot")}}     # the direction of motion picks Mmax
#: the configurations whose union the declared dependencies are (a parameter that moves the
#: structure: BusKinematics' distinguished segment j, driving segment k, prediction model)
CONFIGS = {
    "BusKinematics": [{"j": j, "k": k, "predictionModel": pm} for j in range(5) for k in range(5)
                      for pm in (False, True)],
    "ArticulationDamper": [{"tauP": tau, "bothWays": both} for tau in (0.0, 0.05) for both in (False, True)],
}
PLANTS = sorted(RANGES)


def _range(plant, name):
    ranges = RANGES[plant]
    return ranges.get(name) or ranges[name.split("[")[0]]


class Plant:
    """One plant instantiated with FMPy (FMI 2.0 or 3.0, ME or CS), its knowns and unknowns
    from its model description: the states (the variables the derivatives are of), the Real
    inputs; the derivatives and the Real outputs."""

    def __init__(self, name, version, me, tmp_path, parameters=True, extra=None):
        self.path = fmu_file(name) if version == 2 else fmu3(name)
        md = read_model_description(str(self.path))
        self.md, self.version, self.me = md, version, me
        byname = {v.name: v for v in md.modelVariables}
        self.states = [d.variable.derivative for d in md.derivatives] if me else []
        self.inputs = [v for v in md.modelVariables if v.causality == "input" and v.type in ("Real", "Float64")]
        self.knowns = self.states + self.inputs
        self.unknowns = ([d.variable for d in md.derivatives] if me else []) + \
            [v for v in md.modelVariables if v.causality == "output" and v.type in ("Real", "Float64")]
        unzip = tmp_path / f"{name}{version}{'me' if me else 'cs'}"
        with zipfile.ZipFile(self.path) as z:
            z.extractall(unzip)
        ident = (md.modelExchange if me else md.coSimulation).modelIdentifier
        cls = (FMU2Model if me else FMU2Slave) if version == 2 else (FMU3Model if me else FMU3Slave)
        self.fmu = cls(guid=md.guid, unzipDirectory=str(unzip), modelIdentifier=ident, instanceName="p")
        self.fmu.instantiate()
        if version == 2:
            self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for k, v in {**(PARAMETERS[name] if parameters else {}), **(extra or {})}.items():
            var = byname[k]
            if isinstance(v, bool):
                self.fmu.setBoolean([var.valueReference], [v])
            elif var.type in ("Integer", "Int32", "Enumeration"):
                (self.fmu.setInteger if version == 2 else self.fmu.setInt32)([var.valueReference], [v])
            else:
                self.set_real([var.valueReference], [v])
        self.fmu.exitInitializationMode()
        if me:
            self.fmu.enterContinuousTimeMode()
        self.name = name

    def set_real(self, vrs, values):
        (self.fmu.setReal if self.version == 2 else self.fmu.setFloat64)(vrs, values)

    def get_real(self, vrs):
        return np.array((self.fmu.getReal if self.version == 2 else self.fmu.getFloat64)(vrs))

    def set_point(self, values):
        """the knowns to values (states through fmi*SetContinuousStates, inputs as variables)"""
        ns = len(self.states)
        if ns:
            x = np.array(values[:ns], dtype=float)
            self.fmu.setContinuousStates(x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), ns)
        self.set_real([v.valueReference for v in self.inputs], list(values[ns:]))

    def unknown_values(self):
        return self.get_real([v.valueReference for v in self.unknowns])

    def random_point(self, rng):
        return np.array([rng.uniform(*_range(self.name, v.name)) for v in self.knowns])

    def jacobian(self):
        """J from the FMU's directional derivatives, one unit seed per known"""
        ku = [v.valueReference for v in self.knowns]
        uu = [v.valueReference for v in self.unknowns]
        cols = []
        for j in range(len(ku)):
            seed = [0.0] * len(ku)
            seed[j] = 1.0
            cols.append(self.fmu.getDirectionalDerivative(uu, ku, seed))
        return np.array(cols).T

    def finite_differences(self, point):
        """central differences, Richardson-extrapolated (error O(h^4)), and the scales s_j"""
        scale = np.maximum(1.0, np.abs(point))
        cols = []
        for j in range(len(point)):
            def diff(h):
                up, down = point.copy(), point.copy()
                up[j] += h
                down[j] -= h
                self.set_point(up)
                fu = self.unknown_values()
                self.set_point(down)
                fd = self.unknown_values()
                return (fu - fd) / (2 * h)
            h = 1e-4 * scale[j]
            cols.append((4 * diff(h / 2) - diff(h)) / 3)
        self.set_point(point)
        return np.array(cols).T, scale

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def _compare(p, seeds=SEEDS):
    """the FMU's Jacobian against the finite differences at random points (module docstring)"""
    for s in seeds:
        point = p.random_point(np.random.default_rng(s))
        p.set_point(point)
        D, scale = p.finite_differences(point)
        J = p.jacobian()
        ok, _ = _check(J, D, scale)
        bad = [(p.unknowns[i].name, p.knowns[j].name, J[i, j], D[i, j]) for i, j in zip(*np.nonzero(~ok))]
        assert not bad, f"seed {s}: {len(bad)} entries off, e.g. {bad[:5]}"
        assert np.count_nonzero(J) > len(p.knowns)          # not a Jacobian of zeros


def _check(J, D, scale):
    Js, Ds = J * scale, D * scale
    bound = RTOL * np.abs(Ds).max(axis=1, keepdims=True) + 1e-12
    err = np.abs(Js - Ds)
    return err <= bound, err / np.maximum(bound, 1e-300)


@pytest.mark.parametrize("version", (2, 3))
@pytest.mark.parametrize("me", (True, False), ids=("ME", "CS"))
@pytest.mark.parametrize("plant", PLANTS)
def test_directional_derivatives_equal_finite_differences(plant, version, me, tmp_path):
    p = Plant(plant, version, me, tmp_path)
    try:
        _compare(p)
    finally:
        p.close()


@pytest.mark.parametrize("tyre", (1, 2, 3))
def test_bus_dynamics_tyre_models(tyre, tmp_path):
    """the tyre models beside the linear one (seed 000, II-B): linear with friction (kept below
    its saturation here: mu Fz = 1.6e5 N against C |alpha| <= 1e6 x 0.15 rad), Fiala's brush
    model (the friction limit mu Fz = 3.2e4 N: some axles slide partly), linear scaled"""
    mu = 4.0 if tyre == 1 else 0.8
    p = Plant("BusDynamics", 2, True, tmp_path, extra={"tyreModel": tyre, **{f"mu[{a}]": mu for a in range(1, 9)}})
    try:
        _compare(p)
    finally:
        p.close()


def _declared(p):
    """{unknown value reference: set of known value references} of the FMU's <ModelStructure>
    (FMI 2.0: <Outputs>/<Derivatives> <Unknown> by index; FMI 3.0: <Output> and
    <ContinuousStateDerivative> by value reference), read here with lxml; no attribute: all"""
    with zipfile.ZipFile(p.path) as z:
        root = etree.fromstring(z.read("modelDescription.xml"))
    known = {v.valueReference for v in p.knowns}
    if p.version == 2:
        svs = root.findall("ModelVariables/ScalarVariable")
        vr = {i + 1: int(sv.get("valueReference")) for i, sv in enumerate(svs)
              if sv.find("Real") is not None}
        rows = root.findall("ModelStructure/Outputs/Unknown") + root.findall("ModelStructure/Derivatives/Unknown")
        get = lambda u: vr[int(u.get("index"))]
        deps = lambda u: {vr[int(i)] for i in u.get("dependencies").split() if int(i) in vr}
    else:
        rows = root.findall("ModelStructure/Output") + root.findall("ModelStructure/ContinuousStateDerivative")
        get = lambda u: int(u.get("valueReference"))
        deps = lambda u: {int(i) for i in u.get("dependencies").split()}
    return {get(u): (deps(u) if u.get("dependencies") is not None else known) & known for u in rows}


def _fd_pattern(p, seeds=SEEDS):
    """the knowns each unknown depends on by finite differences: an entry whose scaled
    sensitivity exceeds 1e-8 of its row's largest at some random point (below that: the
    rounding residue of a structural zero, c s - s c)"""
    nonzero = np.zeros((len(p.unknowns), len(p.knowns)), dtype=bool)
    for s in seeds:
        point = p.random_point(np.random.default_rng(s))
        D, scale = p.finite_differences(point)
        Ds = np.abs(D * scale)
        nonzero |= Ds > 1e-8 * Ds.max(axis=1, keepdims=True)
    return {u.valueReference: {p.knowns[j].valueReference for j in np.nonzero(nonzero[i])[0]}
            for i, u in enumerate(p.unknowns)}


@pytest.mark.parametrize("version", (2, 3))
@pytest.mark.parametrize("plant", PLANTS)
def test_model_structure_dependencies_exact(plant, version, tmp_path):
    """in the largest configuration (the union over CONFIGS) the declared dependencies are the
    finite differences' pattern exactly; at the default parameters they contain it"""
    found = {}
    for c, extra in enumerate(CONFIGS.get(plant, [{}])):
        p = Plant(plant, version, True, tmp_path / f"c{c}", extra=extra)
        try:
            declared = _declared(p)
            for u, ks in _fd_pattern(p, seeds=SEEDS if plant not in CONFIGS else (c % 3 + 1,)).items():
                found[u] = found.get(u, set()) | ks
        finally:
            p.close()
    name = {v.valueReference: v.name for v in p.unknowns + p.knowns}
    switches = {(u, k) for u in found for k in declared[u] if (name[u], name[k]) in SWITCHES.get(plant, ())}
    found = {u: ks | {k for uu, k in switches if uu == u} for u, ks in found.items()}
    wrong = {name[u]: (sorted(name[k] for k in declared[u] - found[u]), sorted(name[k] for k in found[u] - declared[u]))
             for u in found if declared[u] != found[u]}
    assert not wrong, f"(declared but zero, nonzero but not declared): {wrong}"
    p = Plant(plant, version, True, tmp_path / "default", parameters=False)
    try:
        found = _fd_pattern(p, seeds=(1,))
    finally:
        p.close()
    missing = {name[u]: sorted(name[k] for k in found[u] - declared[u]) for u in found if found[u] - declared[u]}
    assert not missing, f"nonzero but not declared at the default parameters: {missing}"


@pytest.mark.parametrize("version", (2, 3))
@pytest.mark.parametrize("plant", PLANTS)
def test_the_plants_say_they_provide_them(plant, version):
    """providesDirectionalDerivative="true" (FMI 2.0) / providesDirectionalDerivatives and
    providesAdjointDerivatives="true" (FMI 3.0) on <ModelExchange> and <CoSimulation>"""
    path = fmu_file(plant) if version == 2 else fmu3(plant)
    with zipfile.ZipFile(path) as z:
        root = etree.fromstring(z.read("modelDescription.xml"))
    attrs = ("providesDirectionalDerivative",) if version == 2 else \
        ("providesDirectionalDerivatives", "providesAdjointDerivatives")
    for kind in ("ModelExchange", "CoSimulation"):
        for a in attrs:
            assert root.find(kind).get(a) == "true", (kind, a)


@pytest.mark.parametrize("version", (2, 3))
def test_jacobian_columns_follow_every_change_of_the_point(version, tmp_path):
    """BusDynamics answers a column of the Jacobian at a point it has already differentiated
    from what it computed there (an importer asks a column per state): every answer still
    equals the finite differences at the point as it is now. At one point: the derivatives
    alone, then derivatives and outputs; a new input value at the same states; new states; the
    time moved; a seed of 2.5 (2.5 times the column) and a seed on two states at once (the sum
    of the two columns: J is linear)."""
    p = Plant("BusDynamics", version, True, tmp_path)
    try:
        ders = [d.variable for d in p.md.derivatives]
        all_unknowns = p.unknowns
        point = p.random_point(np.random.default_rng(7))

        def check(unknowns, why):
            p.unknowns = unknowns
            D, scale = p.finite_differences(point)
            J = p.jacobian()
            ok, _ = _check(J, D, scale)
            assert ok.all(), f"{why}: {np.count_nonzero(~ok)} entries off"
            return J

        p.set_point(point)
        J_before = check(ders, "the derivatives alone")
        check(all_unknowns, "derivatives and outputs at the same point")
        delta = next(i for i, v in enumerate(p.knowns) if v.name == "delta[1]")
        point[delta] += 0.05
        p.set_point(point)
        J_after = check(ders, "a new steering angle")
        assert np.abs(J_after - J_before).max() > 1e-3 * np.abs(J_before).max()
        point[:len(p.states)] = p.random_point(np.random.default_rng(8))[:len(p.states)]
        p.set_point(point)
        check(all_unknowns, "new states")
        (p.fmu.setTime if version == 2 else p.fmu.setTime)(1.25)
        p.set_point(point)
        J = check(ders, "the time moved")
        uu = [v.valueReference for v in ders]
        ku = [v.valueReference for v in p.knowns]
        i, j = 3, len(p.states) // 2 + 3           # the yaw angle of module 2, the yaw rate of module 2
        seed = [0.0] * len(ku)
        seed[i] = 2.5
        np.testing.assert_allclose(p.fmu.getDirectionalDerivative(uu, ku, seed), 2.5 * J[:, i], rtol=1e-14, atol=0)
        seed[j] = 1.0
        np.testing.assert_allclose(p.fmu.getDirectionalDerivative(uu, ku, seed), 2.5 * J[:, i] + J[:, j],
                                   rtol=1e-12, atol=1e-12 * np.abs(J).max())
    finally:
        p.unknowns = all_unknowns
        p.close()


@pytest.mark.parametrize("plant", PLANTS)
def test_adjoint_derivative_is_the_transpose(plant, tmp_path):
    """fmi3GetAdjointDerivative: seed^T J for a random seed over the unknowns, J from the
    directional derivatives (checked against finite differences above), to rounding"""
    p = Plant(plant, 3, True, tmp_path)
    try:
        p.set_point(p.random_point(np.random.default_rng(7)))
        J = p.jacobian()
        w = np.random.default_rng(8).uniform(-1, 1, len(p.unknowns))
        adj = np.array(p.fmu.getAdjointDerivative([v.valueReference for v in p.unknowns],
                                                  [v.valueReference for v in p.knowns], list(w),
                                                  nSensitivity=len(p.knowns)))
    finally:
        p.close()
    expected = w @ J
    assert np.allclose(adj, expected, rtol=1e-12, atol=1e-12 * np.abs(w[:, None] * J).max())


def test_a_model_without_them_refuses(tmp_path, capfd):
    """a model without the hook (DampingController) answers fmi2Error, naming the call and why"""
    from fmpy.fmi1 import FMICallException
    path = fmu_file("DampingController")
    md = read_model_description(str(path))
    unzip = tmp_path / "dc"
    with zipfile.ZipFile(path) as z:
        z.extractall(unzip)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=str(unzip), modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="dc")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    inp = next(v for v in md.modelVariables if v.causality == "input" and v.type == "Real")
    out = next(v for v in md.modelVariables if v.causality == "output" and v.type == "Real")
    with pytest.raises(FMICallException, match="fmi2GetDirectionalDerivative"):
        fmu.getDirectionalDerivative([out.valueReference], [inp.valueReference], [1.0])
    fmu.freeInstance()
    assert "fmi2GetDirectionalDerivative: not provided by this FMU (providesDirectionalDerivative = false)" \
        in capfd.readouterr().out      # FMPy's default logger prints the FMU's messages

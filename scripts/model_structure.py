"""Write the exact <ModelStructure> dependencies of a plant into its modelDescription/<Name>.xml
(issue 43), from the built FMU's own directional derivatives.

    .venv/bin/python scripts/model_structure.py MultiAxle3DOF BusDynamics [--fmus DIR]

The model description stays the one source of the FMU's variables and structure: this fills the
``dependencies`` of every <Outputs> and <Derivatives> <Unknown> (FMI 2.0.4, 2.2.8: the knowns an
unknown depends on, the continuous states and the inputs) with the knowns whose column of the
Jacobian is nonzero in that row at any of a few random states and inputs, in the plant's largest
configuration (every module, axle and steerable axle present: PARAMETERS), so that the list is
exact there and a superset in a smaller one. The Jacobian is the FMU's, exact to rounding
(fmi2GetDirectionalDerivative): a structural zero is an exact zero. Rebuild the FMU afterwards
(the archive carries the description). tests/test_directional_derivatives.py checks the result
against finite differences, independently of this script.
"""
import argparse
import ctypes
import re
import shutil
import tempfile
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model

ROOT = Path(__file__).resolve().parents[1]

#: the largest configuration of each plant, and the ranges of the random states and inputs
PARAMETERS = {
    "MultiAxle3DOF": {"n": 6, **{f"steerable[{i}]": True for i in range(1, 7)},
                      **{f"d[{i}]": 0.05 * i for i in range(1, 7)}},
    "BusDynamics": {"nModules": 4, "nAxles": 8, "FzFromMasses": False,
                    **{f"Fz0[{a}]": 40000.0 for a in range(1, 9)}},
    "BusKinematics": {"N": 4, **{f"steerable[{i}]": True for i in range(1, 5)}},
    "ArticulationDamper": {},
}
#: the dependencies are the union over these (parameters that move the structure)
CONFIGS = {
    "BusKinematics": [{"j": j, "k": k, "predictionModel": pm} for j in range(5) for k in range(5)
                      for pm in (False, True)],
    "ArticulationDamper": [{"tauP": tau, "bothWays": both} for tau in (0.0, 0.05) for both in (False, True)],
}
#: dependencies through a switch only (a piecewise constant function: zero derivative where it has
#: one), declared all the same: an importer sorting the equations needs them
SWITCHES = {"ArticulationDamper": {"Mmax": ["LambdaDot"]}}
SPREAD = 0.2        # random states and inputs: start value + SPREAD * uniform(-1, 1) * max(1, |start|)
POINTS = 5


def jacobian(fmu, md, rng):
    """d(derivatives, outputs)/d(states, inputs) at a random point, from the FMU's directional
    derivatives; the unknowns' and knowns' model-description indices"""
    index = {id(v): i + 1 for i, v in enumerate(md.modelVariables)}
    states = [d.variable.derivative for d in md.derivatives]
    inputs = [v for v in md.modelVariables if v.causality == "input" and v.type == "Real"]
    unknowns = [d.variable for d in md.derivatives] + [o.variable for o in md.outputs]
    x = np.array([rng.uniform(-1, 1) * SPREAD for _ in states])
    if md.modelName == "BusDynamics":
        x[6] += 10.0                     # zd[1]: driving forwards at some 10 m/s
    fmu.setContinuousStates(x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(states))
    fmu.setReal([v.valueReference for v in inputs],
                [float(v.start or 0) + SPREAD * rng.uniform(-1, 1) * max(1.0, abs(float(v.start or 0)))
                 for v in inputs])
    knowns = states + inputs
    kr, ur = [v.valueReference for v in knowns], [v.valueReference for v in unknowns]
    J = np.array([fmu.getDirectionalDerivative(ur, kr, list(np.eye(len(kr))[j])) for j in range(len(kr))]).T
    return J, [index[id(v)] for v in unknowns], [index[id(v)] for v in knowns]


def dependencies(name, fmus):
    """{unknown index: [known indices]} of the plant, from its built FMU: the union over CONFIGS"""
    union = {}
    for extra in CONFIGS.get(name, [{}]):
        for u, ks in dependencies_in(name, fmus, {**PARAMETERS[name], **extra}).items():
            union[u] = sorted(set(union.get(u, [])) | set(ks))
    return union


def dependencies_in(name, fmus, parameters):
    """{unknown index: [known indices]} of the plant with these parameters"""
    path = fmus / f"{name}.fmu"
    md = read_model_description(str(path))
    tmp = extract(str(path), tempfile.mkdtemp())
    fmu = FMU2Model(guid=md.guid, unzipDirectory=tmp, modelIdentifier=md.modelExchange.modelIdentifier,
                    instanceName=name)
    try:
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        byname = {v.name: v for v in md.modelVariables}
        for k, v in parameters.items():
            var = byname[k]
            setter = fmu.setBoolean if isinstance(v, bool) else fmu.setInteger if var.type == "Integer" else fmu.setReal
            setter([var.valueReference], [v])
        fmu.exitInitializationMode()
        fmu.enterContinuousTimeMode()
        rng = np.random.default_rng(43)
        nonzero = None
        for _ in range(POINTS):
            J, unknowns, knowns = jacobian(fmu, md, rng)
            # a structural zero can come out as a rounding residue (a rotation and its
            # inverse: c s - s c): below 1e-10 of the row's largest entry is zero
            Js = np.abs(J)
            nz = Js > 1e-10 * Js.max(axis=1, keepdims=True)
            nonzero = nz if nonzero is None else nonzero | nz
        fmu.terminate()
    finally:
        fmu.freeInstance()
        shutil.rmtree(tmp, ignore_errors=True)
    index = {v.name: i + 1 for i, v in enumerate(md.modelVariables)}
    extra = {index[u]: {index[k] for k in ks} for u, ks in SWITCHES.get(name, {}).items()}
    return {u: sorted({knowns[j] for j in np.nonzero(nonzero[i])[0]} | extra.get(u, set()))
            for i, u in enumerate(unknowns)}


def rewrite(xml, deps):
    """the dependencies into <Outputs> and <Derivatives> of the XML text, its layout kept"""
    head, rest = xml.split("<ModelStructure>", 1)
    body, tail = rest.split("<InitialUnknowns>", 1) if "<InitialUnknowns>" in rest else (rest, None)

    def one(m):
        i = int(m.group(1))
        return f'<Unknown index="{i}" dependencies="{" ".join(map(str, deps[i]))}"/>'

    body = re.sub(r'<Unknown index="(\d+)"(?: dependencies="[^"]*")?\s*/>', one, body)
    return head + "<ModelStructure>" + body + ("" if tail is None else "<InitialUnknowns>" + tail)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="+")
    ap.add_argument("--fmus", type=Path, default=ROOT / "fmus")
    args = ap.parse_args()
    for name in args.names:
        path = ROOT / "modelDescription" / f"{name}.xml"
        deps = dependencies(name, args.fmus)
        path.write_text(rewrite(path.read_text(encoding="utf-8"), deps), encoding="utf-8")
        print(f"{path}: {len(deps)} unknowns, {sum(map(len, deps.values()))} dependencies")


if __name__ == "__main__":
    main()

"""Run a portable pack (artibus pack --portable) in another SSP master, in a process
of its own (each master loads the FMUs' libraries itself and logs at the
file-descriptor level; a crash there is its own): ecos (ecospy), libcosim
(libcosimpy) or FMPy's fmpy.ssp.simulate_ssp. Used by tests/test_masters.py and
benchmarks/masters.py.

usage: masters_run.py MASTER PACK STEP STOP OUT.json COMP.VAR ...
       MASTER: ecos | libcosim | fmpy-ssp; STEP, STOP in s

OUT.json: {"ok": bool, "error": the master's message, "names": ["time", COMP.VAR ...],
"rows": [[t, values ...], ...] (t = 0 and every step after it; libcosim's from the first
step on: it initialises in its first step), "wall": seconds in the master's run (set-up,
initialisation, stepping, reading the values)}.

Each master as its documentation says to run it: ecos with EcosSimulation(ssp_path,
step_size) and init(parameter_set="bench") (artibus.bench.portable.PARAMETER_SET), one
step at a time, values by "COMP::VAR"; libcosim with CosimExecution.from_ssp_file(pack,
step) (its fixed-step algorithm, each component at its osp:StepSizeHint), a last-value
observer after each step; fmpy.ssp.simulate_ssp(pack, stop_time, step_size,
parameter_set=...) with the components' inline sets as one ParameterSet (it applies no
bindings itself), its rows (each the values after the step from its time) put at the
step's end.
"""
import json
import math
import sys
import time as _time
import traceback

PARAMETER_SET = "bench"     # artibus.bench.portable.PARAMETER_SET (not imported: the master's process)


def ecos_getters(sim, ids):
    """[(get, id)] for ecos's "COMP::VAR" ids: the getter (real, integer, bool) that reads each
    (ecos has no call that says a variable's type); RuntimeError naming one it has not"""
    from ecospy.lib import EcosLib
    getters = []
    for i in ids:
        for get in (sim.get_real, sim.get_integer, sim.get_bool):
            try:
                get(i)
            except Exception:
                continue
            getters.append((get, i))
            break
        else:
            raise RuntimeError(f"ecos: no variable {i}: {EcosLib.get_last_error()}")
    return getters


def run_ecos(pack, step, stop, names):
    from ecospy import EcosSimulation
    from ecospy.lib import EcosLib
    sim = EcosSimulation(ssp_path=pack, step_size=step)
    try:
        if not sim.init(parameter_set=PARAMETER_SET):
            raise RuntimeError(f"ecos init: {EcosLib.get_last_error()}")
        getters = ecos_getters(sim, [n.replace(".", "::", 1) for n in names])
        rows = [[0.0] + [float(g(i)) for g, i in getters]]
        for k in range(int(round(stop / step))):
            sim.step(1)
            rows.append([(k + 1) * step] + [float(g(i)) for g, i in getters])
        sim.terminate()
        return rows
    finally:
        sim.free()


def run_libcosim(pack, step, stop, names):
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy._internal import get_last_error_message
    log_output_level(CosimLogLevel.ERROR)
    ns = round(step * 1e9)                   # libcosim counts integer nanoseconds
    try:
        ex = CosimExecution.from_ssp_file(pack, step_size=ns)
    except AssertionError:
        raise RuntimeError(f"libcosim: {get_last_error_message()}") from None
    observer = CosimObserver.create_last_value()
    ex.add_observer(observer)
    slaves = {s.name.decode(): s.index for s in ex.slave_infos()}
    reads = []
    for n in names:
        comp, _, var = n.partition(".")
        if comp not in slaves:
            raise RuntimeError(f"libcosim: no slave {comp}")
        refs = {v.name.decode(): (v.reference, v.type) for v in ex.slave_variables(slaves[comp])}
        if var not in refs:
            raise RuntimeError(f"libcosim: no variable {n}")
        reads.append((slaves[comp], *refs[var]))
    get = {CosimVariableType.REAL.value: observer.last_real_values,
           CosimVariableType.INTEGER.value: observer.last_integer_values,
           CosimVariableType.BOOLEAN.value: observer.last_boolean_values}
    groups = {}                  # one observer call per slave and type: (slave, type) -> [(column, reference)]
    for col, (s_, r, t) in enumerate(reads):
        groups.setdefault((s_, t), []).append((col, r))
    calls = [(get[t], s_, [r for _, r in items], [c for c, _ in items]) for (s_, t), items in groups.items()]
    rows = []
    for k in range(int(round(stop / step))):
        if not ex.step(1):
            raise RuntimeError(f"libcosim at t = {k * step:g} s: {get_last_error_message()}")
        row = [0.0] * len(reads)
        for f, s_, refs, cols in calls:
            for c, x in zip(cols, f(s_, refs)):
                row[c] = float(x)
        rows.append([ex.status().current_time * 1e-9] + row)
    return rows


def run_fmpy_ssp(pack, step, stop, names):
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import Parameter, ParameterSet, find_components, read_ssd
    ssd = read_ssd(pack)
    params = []
    for c in find_components(ssd.system):
        for b in c.parameterBindings:
            for pset in b.parameterValues:
                for p in pset.parameters:
                    if p.type == "String":
                        continue                     # simulate_ssp sets Real, Integer, Boolean only
                    v = (float(p.value) if p.type == "Real" else p.value in ("true", "1") if p.type == "Boolean"
                         else int(p.value))
                    params.append(Parameter(name=f"{c.name}.{p.name}", type=p.type, value=v))
    r = simulate_ssp(pack, stop_time=stop, step_size=step, parameter_set=ParameterSet(parameters=params))
    missing = [n for n in names if n not in r.dtype.names]
    if missing:
        raise RuntimeError(f"fmpy.ssp: not recorded: {', '.join(missing)} (it records connectors)")
    n = int(round(stop / step))      # (its loop adds the step to the time: it may run one step more)
    return [[(i + 1) * step] + [float(r[name][i]) for name in names] for i in range(min(n, len(r)))]


RUNS = {"ecos": run_ecos, "libcosim": run_libcosim, "fmpy-ssp": run_fmpy_ssp}


def main(master, pack, step, stop, out, *names):
    step, stop = float(step), float(stop)
    result = {"ok": False, "error": "", "names": ["time", *names], "rows": [], "wall": math.nan}
    t0 = _time.perf_counter()
    try:
        result["rows"] = RUNS[master](pack, step, stop, list(names))
        result["ok"] = True
    except Exception as e:
        result["error"] = f"{type(e).__name__}: {e}".strip()
        traceback.print_exc()
    result["wall"] = _time.perf_counter() - t0
    with open(out, "w") as f:
        json.dump(result, f)
    sys.stdout.flush()


if __name__ == "__main__":
    main(*sys.argv[1:])

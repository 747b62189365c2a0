"""One master's in-process timing of a portable pack (benchmarks/masters.py --speed
starts this in a process of its own per master, as tests/masters_run.py does for
the tests): its Python interface imported first (outside the timing), then REPEAT
times the set-up and the run, each timed with time.perf_counter:

- set-up: reading the SSP, unpacking it and its FMUs, loading the FMUs' libraries,
  instantiating, the recording configured;
- run: the initialisation, every step to STOP, and the recorded values of every
  step read into Python (a table: a NumPy array or a list of rows, as the
  master's interface gives them; made JSON after the timing).

The instances are freed after each repetition, outside the timing. Each master is
driven through its own Python interface as its documentation says
(tests/masters_run.py, the guide's "Other SSP masters"), in two ways where it has
two ways of recording:

  artibus           Simulation(PACK, algorithm=...) + Simulation.run(): the C core
                    records every output (the Result's table)
  ecos              EcosSimulation(ssp_path, step_size) + init(parameter_set="bench"),
                    step(n) in one call, its own recorder (add_csv_writer with the
                    variables registered: written in C++ at every step) read back
                    with NumPy -- ecos's fastest way to every step's values
  ecos-py           the same, one step at a time, each value read by get_real
                    (tests/masters_run.py's way)
  libcosim          CosimExecution.from_ssp_file(pack, step ns), a buffered
                    time-series observer started for every variable (recorded in
                    C++ at every step), step(n) in one call, the samples read by
                    time_series_real_samples -- libcosim's fastest way
  libcosim-py       the same, one step at a time, a last-value observer read after
                    each step (tests/masters_run.py's way)

usage: masters_timed.py SPEC.json OUT.json
  SPEC: {"master", "pack", "step", "stop", "repeat", "names": ["COMP.VAR", ...],
         "algorithm": "gauss-seidel" | "jacobi" (artibus only), "csv": a path (optional:
         the last table written there as CSV, not into OUT)}
  OUT:  {"ok", "error", "setup": [s ...], "run": [s ...], "names": ["time", ...],
         "rows": the last repetition's [[t, values ...] ...]}
"""
import json
import math
import os
import sys
import tempfile
import time
import traceback

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from masters_run import PARAMETER_SET, ecos_getters  # noqa: E402  (the tests' way of driving ecos, one copy)


def artibus_master(spec):
    from artibus.runner import Simulation

    def setup():
        return Simulation(spec["pack"], algorithm=spec.get("algorithm", "gauss-seidel"))

    def run(sim):
        r = sim.run()
        return r.array()[:, [r.names.index(n) for n in ["time", *spec["names"]]]]
    return setup, run, lambda sim: sim.close()


def _ecos(spec, recorder):
    from ecospy import EcosSimulation
    from ecospy.lib import EcosLib
    EcosLib.set_log_level("err")
    step, n = spec["step"], round(spec["stop"] / spec["step"])
    ids = [v.replace(".", "::", 1) for v in spec["names"]]
    csv = os.path.join(tempfile.mkdtemp(prefix="ecos-"), "result.csv")

    def setup():
        sim = EcosSimulation(ssp_path=spec["pack"], step_size=step)
        if recorder:
            sim.add_csv_writer(csv, identifiers=ids)
        return sim

    def run(sim):
        if not sim.init(parameter_set=PARAMETER_SET):
            raise RuntimeError(f"ecos init: {EcosLib.get_last_error()}")
        if recorder:
            import numpy as np
            sim.step(n)
            sim.terminate()                  # the writer flushes its file here
            with open(csv) as f:
                header = [h.strip() for h in f.readline().split(",")]
                table = np.loadtxt(f, delimiter=",", ndmin=2)
            col = {h.rsplit("[", 1)[0]: k for k, h in enumerate(header)}
            return table[:, [col["time"]] + [col[i] for i in ids]]
        getters = ecos_getters(sim, ids)
        rows = [[0.0] + [float(g(i)) for g, i in getters]]
        for k in range(n):
            sim.step(1)
            rows.append([(k + 1) * step] + [float(g(i)) for g, i in getters])
        sim.terminate()
        return rows
    return setup, run, lambda sim: sim.free()


def _libcosim(spec, recorder):
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy._internal import get_last_error_message
    log_output_level(CosimLogLevel.ERROR)
    step, n = spec["step"], round(spec["stop"] / spec["step"])
    ns = round(step * 1e9)                   # libcosim counts integer nanoseconds

    def setup():
        try:
            ex = CosimExecution.from_ssp_file(spec["pack"], step_size=ns)
        except AssertionError:
            raise RuntimeError(f"libcosim: {get_last_error_message()}") from None
        slaves = {s.name.decode(): s.index for s in ex.slave_infos()}
        refs = {}
        reads = []
        for v in spec["names"]:
            comp, _, var = v.partition(".")
            if comp not in refs:
                refs[comp] = {x.name.decode(): (x.reference, x.type) for x in ex.slave_variables(slaves[comp])}
            reads.append((slaves[comp], *refs[comp][var]))
        if recorder:
            obs = CosimObserver.create_time_series(buffer_size=n + 1)
            ex.add_observer(obs)
            for s, r, t in reads:
                obs.start_time_series(s, r, CosimVariableType(t))
        else:
            obs = CosimObserver.create_last_value()
            ex.add_observer(obs)
        return ex, obs, reads

    def run(state):
        ex, obs, reads = state
        if recorder:
            import numpy as np
            if not ex.step(n):
                raise RuntimeError(f"libcosim: {get_last_error_message()}")
            k = np.arange(1, n + 1)           # the rows: after each base step (as its last-value observer)
            cols = [k * ns * 1e-9]            # (its time in ns, as execution.status().current_time)
            for s, r, t in reads:
                steps, values = samples(obs, s, r, t, n + 1)
                # a component at a multiple of the base step has a sample at its own steps
                # only: each row takes the latest at or before its base step
                cols.append(values[np.searchsorted(steps, k, side="right") - 1])
            return np.column_stack(cols)
        get = {CosimVariableType.REAL.value: obs.last_real_values,
               CosimVariableType.INTEGER.value: obs.last_integer_values,
               CosimVariableType.BOOLEAN.value: obs.last_boolean_values}
        groups = {}
        for col, (s_, r, t) in enumerate(reads):
            groups.setdefault((s_, t), []).append((col, r))
        calls = [(get[t], s_, [r for _, r in items], [c for c, _ in items]) for (s_, t), items in groups.items()]
        rows = []
        for k in range(n):
            if not ex.step(1):
                raise RuntimeError(f"libcosim at t = {k * step:g} s: {get_last_error_message()}")
            row = [0.0] * len(reads)
            for f, s_, rs, cs in calls:
                for c, x in zip(cs, f(s_, rs)):
                    row[c] = float(x)
            rows.append([ex.status().current_time * 1e-9] + row)
        return rows
    return setup, run, lambda state: None        # freed with the execution object


def samples(obs, slave, ref, vtype, count):
    """(step numbers, values) of a time-series observer's variable from step 0 on, through
    libcosim's C function cosim_observer_slave_get_real/integer_samples into NumPy arrays
    (libcosimpy's time_series_real_samples drops step 0's sample: it counts entries by
    their step number, 0 taken as empty)."""
    import ctypes
    import numpy as np
    from libcosimpy._internal import libcosimc
    from libcosimpy.CosimEnums import CosimVariableType
    real = vtype == CosimVariableType.REAL.value
    values = np.zeros(count, dtype=np.float64 if real else np.int32)
    steps, times = np.zeros(count, dtype=np.int64), np.zeros(count, dtype=np.int64)
    f = getattr(libcosimc(), "cosim_observer_slave_get_real_samples" if real
                else "cosim_observer_slave_get_integer_samples")
    f.restype = ctypes.c_int64
    f.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint32, ctypes.c_int64, ctypes.c_size_t,
                  ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
    got = f(ctypes.cast(obs.ptr(), ctypes.c_void_p), slave, ref, 0, count, values.ctypes.data, steps.ctypes.data,
            times.ctypes.data)
    if got < 0:
        raise RuntimeError(f"libcosim: no samples of slave {slave} variable {ref}")
    return steps[:got], values[:got].astype(float)


MASTERS = {"artibus": artibus_master,
           "ecos": lambda s: _ecos(s, True), "ecos-py": lambda s: _ecos(s, False),
           "libcosim": lambda s: _libcosim(s, True), "libcosim-py": lambda s: _libcosim(s, False)}


def main(spec_path, out_path):
    with open(spec_path) as f:
        spec = json.load(f)
    out = {"ok": False, "error": "", "setup": [], "run": [], "names": ["time", *spec["names"]], "rows": []}
    try:
        setup, run, free = MASTERS[spec["master"]](spec)     # the imports, outside the timing
        for _ in range(spec["repeat"]):
            t0 = time.perf_counter()
            sim = setup()
            t1 = time.perf_counter()
            rows = run(sim)
            t2 = time.perf_counter()
            free(sim)
            del sim
            out["setup"].append(t1 - t0)
            out["run"].append(t2 - t1)
        if spec.get("csv"):          # as a command: the table to a CSV file, as `artibus run -o`
            import numpy as np
            np.savetxt(spec["csv"], np.asarray(rows, dtype=float), delimiter=",", fmt="%.12g",
                       header=",".join(out["names"]), comments="")
        else:
            out["rows"] = [[float(x) for x in row] for row in rows]     # (outside the timing: for the JSON)
        out["ok"] = True
    except Exception as e:
        out["error"] = f"{type(e).__name__}: {e}".strip()
        traceback.print_exc()
    with open(out_path, "w") as f:
        json.dump(out, f)


if __name__ == "__main__":
    main(*sys.argv[1:])

"""Load one FMU in libcosim (libcosimpy from PyPI; libcosim reads the FMU through the FMI
Library, FMIL) and, given a stop time, run it as Co-Simulation at a fixed step. Run by
tests/test_fmil.py in a process of its own, so that what libcosim and FMIL log (through
libcosim's logger, to the process's stdout/stderr at the file-descriptor level) is read as
the process's output.

usage: libcosim_run.py FMU START STOP STEP OUT.json [VR=VALUE ...]
       (times in s; STOP = START: load only; VR=VALUE: a Real variable's initial value)

OUT.json: {"slave": index or -1, "error": libcosim's last error message, "variables":
[[name, valueReference, type, causality], ...] as libcosim lists them, and after a run "ok",
"time" (s) and "values": {"Real"|"Integer"|"Boolean": {valueReference: value}} of every
output at the end time (last-value observer)}. libcosim counts time in integer nanoseconds.
"""
import json
import sys

from libcosimpy.CosimEnums import CosimVariableCausality, CosimVariableType
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave
from libcosimpy._internal import get_last_error_message


def ns(seconds):
    return round(float(seconds) * 1e9)


def main(fmu, start, stop, step, out, *initial):
    if ns(start) != 0:
        sys.exit("libcosim_run.py: libcosimpy's CosimExecution.from_step_size starts at t = 0")
    # DEBUG: FMIL's own account of what it parsed, beside its warnings and errors
    log_output_level(CosimLogLevel.DEBUG)
    execution = CosimExecution.from_step_size(ns(step))
    slave = CosimLocalSlave(fmu_path=fmu, instance_name="fmu")
    index = execution.add_local_slave(slave)
    result = {"slave": index, "error": get_last_error_message() if index < 0 else ""}
    if index >= 0:
        variables = execution.slave_variables(index)
        result["variables"] = [[v.name.decode(), v.reference, CosimVariableType(v.type).name,
                                CosimVariableCausality(v.causality).name] for v in variables]
        for item in initial:
            vr, value = item.split("=")
            if not execution.real_initial_value(index, int(vr), float(value)):
                sys.exit(f"libcosim_run.py: initial value {item}: {get_last_error_message()}")
        if ns(stop) > ns(start):
            observer = CosimObserver.create_last_value()
            execution.add_observer(observer)
            result["ok"] = execution.simulate_until(ns(stop))
            result["error"] = get_last_error_message()
            result["time"] = execution.status().current_time * 1e-9
            outputs = {}
            for v in variables:
                if v.causality == CosimVariableCausality.OUTPUT.value:
                    outputs.setdefault(CosimVariableType(v.type).name, []).append(v.reference)
            read = {"REAL": ("Real", observer.last_real_values),
                    "INTEGER": ("Integer", observer.last_integer_values),
                    "BOOLEAN": ("Boolean", observer.last_boolean_values)}
            result["values"] = {}
            for kind, refs in outputs.items():
                if kind in read:
                    tname, get = read[kind]
                    result["values"][tname] = dict(zip(map(str, refs), get(index, refs)))
    with open(out, "w") as f:
        json.dump(result, f)
    sys.stdout.flush()


if __name__ == "__main__":
    main(*sys.argv[1:])

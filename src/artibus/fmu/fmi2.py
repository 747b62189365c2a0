"""FMI 2.0 Co-Simulation, one instance (``Calls``): FMPy's FMU2Slave with the calls artibus
makes, by Variable (artibus.fmu.model), and its log: every message of the instance goes to a
list of its own, through FMPy's logger proxy (``_callbacks``, ``claim_logger_proxy``).

The calls follow FMI 2.0.4's state machine (section 4.2.4, "State Machine of Calling
Sequence from Master to Slave"): instantiate, setupExperiment, enterInitializationMode,
the values, exitInitializationMode, doStep ..., terminate, freeInstance. An FMI 2.0 FMU ends
the run itself with fmi2DoStep's fmi2Discard and fmi2Terminated (FMI 2.0.4, 4.2.3:
fmi2GetBooleanStatus; artibus.fmu.result.terminated)."""
from fmpy.fmi2 import FMU2Slave

#: the get/set call of each FMI 2.0 type (an Enumeration is an fmi2Integer, FMI 2.0.4 2.2.7)
ACCESSOR = {"Real": "Real", "Integer": "Integer", "Enumeration": "Integer",
            "Boolean": "Boolean", "String": "String"}


def _callbacks(log):
    """FMI callbacks of one instance, whose messages go to ``log`` only
    ("[status] category: message").

    FMPy's logger proxy (fmpy/logging) formats the printf arguments in C and
    then calls the one logger it keeps in a static pointer, the last one given
    to addLoggerProxy, passing the componentEnvironment through. Every
    instance here gets a callback set of its own whose componentEnvironment is
    a number naming its log, and the proxy's logger is one dispatcher for the
    whole process: each message reaches the log of the instance that sent it,
    whichever was instantiated last. The dispatcher lives as long as the
    process, so the proxy's pointer never dangles."""
    from ctypes import byref
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE
    env = next(_ENVS)
    _LOGS[env] = log
    cb = fmi2CallbackFunctions()
    cb.logger = _dispatcher()
    from artibus.fmu import memory     # the process's calloc/free (a preloaded ASan sees the FMUs' heap)
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(memory.calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(memory.free)
    cb.componentEnvironment = env
    claim_logger_proxy()
    _proxy().addLoggerProxy(byref(cb))
    cb._env = env
    return cb


_LOGS = {}                       # componentEnvironment -> that instance's log
_ENVS = iter(range(1, 2**62))
_DISPATCH = []                   # the process's one dispatcher (kept alive here)
_STATUS = ["OK", "Warning", "Discard", "Error", "Fatal", "Pending"]


def _proxy():
    import fmpy.logging
    return fmpy.logging


def _dispatcher():
    if not _DISPATCH:
        from fmpy.fmi2 import fmi2CallbackLoggerTYPE

        from fmpy.fmi1 import printLogMessage

        def dispatch(env, instance, status, category, message):
            log = _LOGS.get(env)
            if log is not None:
                log.append(f"[{_STATUS[status] if 0 <= status < 6 else status}] "
                           f"{(category or b'').decode(errors='replace')}: "
                           f"{(message or b'').decode(errors='replace')}")
            else:                        # an FMU FMPy instantiated in this process: as FMPy prints it
                printLogMessage(env, instance, status, category, message or b"")
        _DISPATCH.append(fmi2CallbackLoggerTYPE(dispatch))
    return _DISPATCH[0]


def claim_logger_proxy():
    """Make the dispatcher FMPy's proxied logger again: FMPy's own
    instantiations (fmpy.simulate_fmu in the same process) take the proxy's
    one pointer for their logger, which dangles once they are gone; called
    before each run and initialisation here."""
    from ctypes import byref
    from fmpy.fmi2 import fmi2CallbackFunctions
    cb = fmi2CallbackFunctions()
    cb.logger = _dispatcher()
    _proxy().addLoggerProxy(byref(cb))


class Calls:
    """The FMI 2.0 calls of one Co-Simulation instance (``slave``: FMPy's FMU2Slave)."""
    fmi = 2

    def __init__(self, model, unzip_dir, instance_name):
        self.model = model
        self.slave = FMU2Slave(guid=model.guid, unzipDirectory=unzip_dir,
                               modelIdentifier=model.coSimulation.modelIdentifier,
                               instanceName=instance_name)
        self._callbacks = None

    def instantiate(self, log, logging=False):
        self._callbacks = _callbacks(log)
        try:
            self.slave.instantiate(loggingOn=logging, callbacks=self._callbacks)
        except BaseException:
            _LOGS.pop(self._callbacks._env, None)
            raise

    def enter_initialization(self, start_time=0.0, tolerance=None, stop_time=None):
        """setupExperiment and enterInitializationMode (FMI 2.0.4, 4.2.1)"""
        self.slave.setupExperiment(tolerance=tolerance, startTime=start_time, stopTime=stop_time)
        self.slave.enterInitializationMode()

    def exit_initialization(self):
        self.slave.exitInitializationMode()

    def set(self, variables, values):
        """Set each Variable to its value (Python values: float, int, bool, str), one call per type."""
        for t, items in _by_accessor(variables, values).items():
            getattr(self.slave, f"set{t}")([v.valueReference for v, _ in items], [x for _, x in items])

    def get(self, variables):
        """The Variables' values as Python values (float; int for an Integer or Enumeration;
        bool; str), one call per type."""
        out = [None] * len(variables)
        groups = {}
        for i, v in enumerate(variables):
            groups.setdefault(ACCESSOR[v.type], []).append((i, v.valueReference))
        for t, items in groups.items():
            got = getattr(self.slave, f"get{t}")([vr for _, vr in items])
            for (i, _), x in zip(items, got):
                out[i] = (bool(x) if t == "Boolean" else
                          x.decode("utf-8", errors="replace") if isinstance(x, bytes) else x)
        return out

    def do_step(self, t, h):
        """One step from t to t + h: None (an FMI 2.0 FMU ends the run with fmi2Discard, an
        FMICallException the caller reads with artibus.fmu.result.terminated)."""
        self.slave.doStep(t, h)
        return None

    def last_successful_time(self):
        """where a failed step stopped (fmi2GetRealStatus(fmi2LastSuccessfulTime), FMI 2.0.4 4.2.3)"""
        return self.slave.getRealStatus(2)

    def free(self):
        try:
            self.slave.freeInstance()
        finally:
            if self._callbacks is not None:
                _LOGS.pop(self._callbacks._env, None)   # the instance is gone: it logs no more


def _by_accessor(variables, values):
    groups = {}
    for v, x in zip(variables, values):
        groups.setdefault(ACCESSOR[v.type], []).append((v, x))
    return groups

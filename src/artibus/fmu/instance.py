"""An FMU instance with its variables addressed by name (``Fmu``): FMPy's
FMU2Slave (or FMU3Slave, an FMI 3.0 FMU) with a log of its own, the process's
memory callbacks (artibus.fmu.memory) and model descriptions read once per content."""
import shutil

from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave

from artibus import cache
from artibus.base import ArtibusError
from artibus.bench.fmi import FMI2_TYPE, fmi2_view, fmi_major  # noqa: F401


def _declared_version(path):
    """The fmiVersion attribute of an FMU's modelDescription.xml, read without validating
    anything else (an FMI 1.0 or 4.0 FMU fails FMPy's reading for other reasons first);
    None where it cannot be read."""
    import zipfile

    from lxml import etree
    try:
        with zipfile.ZipFile(path) as z, z.open("modelDescription.xml") as f:
            for _, el in etree.iterparse(f, events=("start",), resolve_entities=False, no_network=True):
                return el.get("fmiVersion")
    except Exception:
        return None


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


#: the FMI 3.0 accessor of each (FMU3Slave.get<T>/set<T>); an Enumeration is an Int64
FMI3_ACCESSOR = {"Real": "Float64", "Integer": "Int32", "Enumeration": "Int64",
                 "Boolean": "Boolean", "String": "String"}


def _fmi3_logger(log):
    from fmpy.fmi3 import fmi3LogMessageCallback

    def logger(env, status, category, message):
        log.append(f"[{_STATUS[status] if 0 <= status < 6 else status}] "
                   f"{(category or b'').decode(errors='replace')}: "
                   f"{(message or b'').decode(errors='replace')}")
    return fmi3LogMessageCallback(logger)


_MDS = {}                        # modelDescription.xml's (CRC-32, size) -> its description
_MDS_KEPT = 64


def _model_description(path):
    """fmpy.read_model_description (validated against the XSD), once per content:
    an FMU whose modelDescription.xml has the CRC-32 and size of one read before
    (the zip's directory says, without unpacking) gets that description again. A
    bench's instances of one FMU, each run's unpacked copy of it and a sweep's
    cases parse it once; the last _MDS_KEPT descriptions are kept."""
    import zipfile
    try:
        with zipfile.ZipFile(path) as z:
            info = z.getinfo("modelDescription.xml")
        key = (info.CRC, info.file_size)
    except (OSError, KeyError, zipfile.BadZipFile):
        return read_model_description(path)       # its own error, named
    md = _MDS.get(key)
    if md is None:
        md = _stored_description(path)
        if len(_MDS) >= _MDS_KEPT:
            _MDS.pop(next(iter(_MDS)))
        _MDS[key] = md
    return md


def _stored_description(path):
    """read_model_description(path), parsed and validated once per content of
    the FMU and kept beside its unpacked copy (artibus.cache.stored), for the
    next process; under FMPy's version, as its classes pickle."""
    import fmpy
    if cache.root() is None:          # (the cache off: nothing kept)
        return read_model_description(path)
    try:
        entry, temporary = cache.unpacked(path)
    except Exception:                 # a broken archive: read_model_description names it
        return read_model_description(path)
    if temporary:
        shutil.rmtree(entry, ignore_errors=True)
        return read_model_description(path)
    return cache.stored(entry, f"modelDescription-fmpy-{fmpy.__version__}", lambda: read_model_description(path))


class Fmu:
    """An FMU instance with the variables addressed by name."""

    def __init__(self, path, instance_name="artibus", logging=False):
        from pathlib import Path
        self.path = str(path)
        if not Path(self.path).is_file():
            raise ArtibusError(f"{self.path}: no such FMU file")
        try:
            self.md = _model_description(self.path)
        except Exception as e:   # not a zip, no or a broken modelDescription.xml, another FMI version
            version = _declared_version(self.path)
            if version is not None and fmi_major(version) is None:
                raise ArtibusError(f"{self.path}: says fmiVersion=\"{version}\": artibus runs FMI 2.0 and 3.0 "
                                   "FMUs (any 3.x the FMI 3.0 schema allows)") from None
            raise ArtibusError(f"{self.path}: not a readable FMI 2.0 or 3.0 FMU: {e}") from None
        self.fmi = fmi_major(self.md.fmiVersion)
        if self.fmi is None:
            raise ArtibusError(f"{self.path}: {self.md.modelName} says fmiVersion=\"{self.md.fmiVersion}\": "
                               "artibus runs FMI 2.0 and 3.0 FMUs (any 3.x the FMI 3.0 schema allows)")
        if self.md.coSimulation is None:
            raise ArtibusError(f"{self.path}: {self.md.modelName} has no Co-Simulation interface "
                               "(artibus runs FMUs in Co-Simulation)")
        #: FMI 3.0: each variable's own type (Float32, UInt16, ...), whose get/set it is read with
        self.fmi3_type = {}
        if self.fmi == 3:    # as FMI 2.0 names the types (the same variables: tests/test_fmi3.py)
            self.fmi3_type = {v.name: "Int64" if v.type == "Enumeration" else v.type
                              for v in self.md.modelVariables}
            try:
                self.md = fmi2_view(self.md, strict=False)
            except ArtibusError as e:
                raise ArtibusError(f"{self.path}: {e}") from None
        self.vars = {v.name: v for v in self.md.modelVariables if v.causality != "independent"}
        self.log = []
        self.instance_name = instance_name
        self._dir, self._own_dir = None, False
        try:
            # unpacked once per content and kept (artibus.cache), or into a temporary directory
            self._dir, self._own_dir = cache.unpacked(self.path)
            self._dir = str(self._dir)
            if self.fmi == 3:
                from fmpy.fmi3 import FMU3Slave
                self.slave = FMU3Slave(guid=self.md.instantiationToken, unzipDirectory=self._dir,
                                       modelIdentifier=self.md.coSimulation.modelIdentifier,
                                       instanceName=instance_name)
            else:
                self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self._dir,
                                       modelIdentifier=self.md.coSimulation.modelIdentifier,
                                       instanceName=instance_name)
        except ArtibusError:     # the archive refused or not unpacked (artibus.cache removed its copy)
            self._remove_dir()
            raise
        except Exception as e:   # a missing or broken binary
            self._remove_dir()
            raise ArtibusError(f"{self.path}: {self.md.modelName}'s binary cannot be loaded: {e}") from None
        self._callbacks = _callbacks(self.log)
        try:
            if self.fmi == 3:
                self._logger = _fmi3_logger(self.log)
                self.slave.instantiate(loggingOn=logging, logMessage=self._logger)
            else:
                self.slave.instantiate(loggingOn=logging, callbacks=self._callbacks)
        except Exception:
            self._remove_dir()
            _LOGS.pop(self._callbacks._env, None)
            raise ArtibusError(f"{self.path}: {self.md.modelName} could not be instantiated: "
                               f"{' '.join(self.log) or 'no message'}") from None

    def _remove_dir(self):
        """The unpacked FMU removed when it is this instance's own (a cache entry stays)."""
        if self._dir and self._own_dir:
            shutil.rmtree(self._dir, ignore_errors=True)

    def var(self, name):
        try:
            return self.vars[name]
        except KeyError:
            from artibus.bench.parameters import no_variable
            raise ArtibusError(f"{self.path}: {no_variable(self.md, name)}") from None

    def set_values(self, values):
        """Set each {name: value}, the value checked against the variable's
        declared type first (artibus.bench.parameters.coerce: no rounding, no
        "yes" for true, an Enumeration by item name or value)."""
        from artibus.bench.parameters import coerce
        for name, value in values.items():
            v = self.var(name)
            try:
                x = coerce(v, value, finite=False)     # NaN, Inf: the FMU refuses them, naming them
            except ValueError as e:
                raise ArtibusError(f"{self.instance_name}.{name} = {value!r}: not a valid {v.type} "
                                   f"for {self.md.modelName}: {e}") from None
            vr = [v.valueReference]
            if self.fmi == 3:
                getattr(self.slave, f"set{self.fmi3_type[name]}")(vr, [x])   # (coerce: in the type's range)
            elif v.type == "Real":
                self.slave.setReal(vr, [x])
            elif v.type in ("Integer", "Enumeration"):
                self.slave.setInteger(vr, [x])
            elif v.type == "Boolean":
                self.slave.setBoolean(vr, [x])
            else:
                self.slave.setString(vr, [x])

    def get(self, *names):
        """The Real variables' values (fmi2GetReal, fmi3GetFloat64, in one call)."""
        reals = [self.var(n).valueReference for n in names]
        return self.slave.getFloat64(reals) if self.fmi == 3 else self.slave.getReal(reals)

    def get_values(self, names):
        """The values of variables of any type, as Python values: float, int
        (Integer, Enumeration), bool, str; one call per type."""
        out = [None] * len(names)
        by_type = {}
        for i, n in enumerate(names):
            v = self.var(n)
            t = self.fmi3_type[n] if self.fmi == 3 else "Integer" if v.type == "Enumeration" else v.type
            by_type.setdefault(t, []).append((i, v.valueReference))
        for t, items in by_type.items():
            got = getattr(self.slave, f"get{t}")([vr for _, vr in items])
            for (i, _), x in zip(items, got):
                out[i] = (bool(x) if t == "Boolean" else x.decode("utf-8", errors="replace")
                          if t == "String" and isinstance(x, bytes) else x)   # FMI 3.0: str already
        return out

    def enter_initialization_mode(self, start_time=0.0):
        """FMI 2.0: setupExperiment and enterInitializationMode; FMI 3.0:
        enterInitializationMode with the start time."""
        if self.fmi == 3:
            self.slave.enterInitializationMode(startTime=start_time)
        else:
            self.slave.setupExperiment(startTime=start_time)
            self.slave.enterInitializationMode()

    def do_step(self, t, h):
        """One step from t to t + h. None, or where the FMU ended the simulation itself:
        FMI 3.0's fmi3DoStep with terminateSimulation (FMI 3.0 4.2.1; an FMI 2.0 FMU says so
        with fmi2Discard, an FMICallException, artibus.fmu.result.terminated)."""
        if self.fmi == 3:
            _, terminate, _, last = self.slave.doStep(t, h)
            return last if terminate else None
        self.slave.doStep(t, h)
        return None

    def last_successful_time(self):
        """where a failed step stopped (fmi2GetRealStatus(fmi2LastSuccessfulTime);
        FMI 3.0: the time variable, the instance's time)"""
        if self.fmi == 3:
            return self.slave.getFloat64([next(v.valueReference for v in self.md.modelVariables
                                               if v.causality == "independent")])[0]
        return self.slave.getRealStatus(2)  # fmi2LastSuccessfulTime

    def initialize(self, values, start_time=0.0):
        """setupExperiment, the values set in initialisation mode, exit it:
        the instance is ready to step from start_time. Returns self."""
        claim_logger_proxy()
        try:
            self.enter_initialization_mode(start_time)
            self.set_values(values)
            self.slave.exitInitializationMode()
        except Exception:
            self.close()
            raise
        return self

    def close(self):
        """Free the instance and its unpacked files; again is a no-op."""
        if getattr(self, "_closed", False):
            return
        self._closed = True
        try:
            self.slave.freeInstance()
        finally:
            self._remove_dir()
            _LOGS.pop(self._callbacks._env, None)   # the instance is gone: it logs no more

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

"""An FMU instance with its variables addressed by name (``Fmu``): its Model (artibus.fmu.model,
one for FMI 2.0 and 3.0), the calls of its FMI version (artibus.fmu.fmi2, artibus.fmu.fmi3:
FMPy's FMU2Slave or FMU3Slave) with a log of its own, and model descriptions read once per
content."""
import shutil

from artibus import cache
from artibus.base import ArtibusError
from artibus.bench.fmi import fmi_major
from artibus.fmu import fmi2, fmi3
from artibus.fmu.fmi2 import claim_logger_proxy  # noqa: F401
from artibus.fmu.model import model_of, read_description


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
        return read_description(path)             # its own error, named
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
        return read_description(path)
    try:
        entry, temporary = cache.unpacked(path)
    except Exception:                 # a broken archive: read_model_description names it
        return read_description(path)
    if temporary:
        shutil.rmtree(entry, ignore_errors=True)
        return read_description(path)
    return cache.stored(entry, f"modelDescription-fmpy-{fmpy.__version__}-a1", lambda: read_description(path))


class Fmu:
    """An FMU instance with the variables addressed by name: ``md`` its Model, ``vars`` its
    Variables by name, ``calls`` the calls of its FMI version (``slave``: FMPy's instance),
    ``log`` its messages. ``event_mode``: an FMI 3.0 instance made with eventModeUsed (its
    events and clocks in Event Mode: artibus.fmu.fmi3)."""

    def __init__(self, path, instance_name="artibus", logging=False, event_mode=False, interface="cs"):
        from pathlib import Path
        self.path = str(path)
        if not Path(self.path).is_file():
            raise ArtibusError(f"{self.path}: no such FMU file")
        self.md = read_model(self.path)
        self.fmi = self.md.fmi
        self.interface = interface       # "cs", or "me": Model Exchange through the ME facade (artibus.fmu.me)
        if interface == "me" and self.md.modelExchange is None:
            raise ArtibusError(f"{self.path}: {self.md.modelName} has no Model Exchange interface "
                               "(--fmi-type me); it runs in Co-Simulation")
        if interface != "me" and self.md.coSimulation is None:
            me = " (it has Model Exchange: --fmi-type me)" if self.md.modelExchange is not None else ""
            raise ArtibusError(f"{self.path}: {self.md.modelName} has no Co-Simulation interface{me}")
        self.vars = {v.name: v for v in self.md.modelVariables if v.causality != "independent"}
        self.log = []
        self.instance_name = instance_name
        self._dir, self._own_dir = None, False
        try:
            # unpacked once per content and kept (artibus.cache), or into a temporary directory
            self._dir, self._own_dir = cache.unpacked(self.path)
            self._dir = str(self._dir)
            if interface == "me":
                from artibus.fmu import me
                self.calls = me.calls(self.md, self._dir, instance_name)
            else:
                self.calls = (fmi3 if self.fmi == 3 else fmi2).Calls(self.md, self._dir, instance_name)
        except ArtibusError:     # the archive refused or not unpacked (artibus.cache removed its copy)
            self._remove_dir()
            raise
        except Exception as e:   # a missing or broken binary
            self._remove_dir()
            raise ArtibusError(f"{self.path}: {self.md.modelName}'s binary cannot be loaded: {e}") from None
        self.slave = self.calls.slave
        if event_mode and self.fmi != 3:
            self._remove_dir()
            raise ArtibusError(f"{self.path}: {self.md.modelName} is an FMI 2.0 FMU: no Event Mode")
        try:
            if self.fmi == 3:
                self.calls.instantiate(self.log, logging, event_mode=event_mode)
            else:
                self.calls.instantiate(self.log, logging)
        except ArtibusError as e:
            self._remove_dir()
            raise ArtibusError(f"{self.path}: {e}") from None
        except Exception:
            self._remove_dir()
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
        "yes" for true, an Enumeration by item name or value, in the type's range;
        an array: a sequence of its values, each checked)."""
        self.calls.set([self.var(n) for n in values], self._checked(values))

    def _checked(self, values):
        """Each value of {name: value} as its variable's type takes it (coerce), in order."""
        from artibus.bench.parameters import coerce
        checked = []
        for name, value in values.items():
            v = self.var(name)
            try:
                x = ([coerce(v, e, finite=False) for e in value] if v.shape else
                     coerce(v, value, finite=False))    # NaN, Inf: the FMU refuses them, naming them
            except (TypeError, ValueError) as e:
                raise ArtibusError(f"{self.instance_name}.{name} = {value!r}: not a valid {v.type} "
                                   f"for {self.md.modelName}: {e}") from None
            checked.append(x)
        return checked

    def get(self, *names):
        """get_values of the variables named (a Real's value a float)."""
        return self.get_values(names)

    def get_values(self, names):
        """The values of variables of any type, as Python values: float, int
        (Integer, Enumeration), bool, str; an array as the list of its values."""
        return self.calls.get([self.var(n) for n in names])

    def configure(self, values):
        """The structural parameters {name: value} set in Configuration Mode (FMI 3.0 only), the
        model's arrays resized by them: ``md`` and ``vars`` are this instance's own from then on."""
        if not values:
            return
        from artibus.fmu.model import Model
        variables = [self.var(n) for n in values]
        for v in variables:
            if v.causality != "structuralParameter" or self.fmi != 3:
                raise ArtibusError(f"{self.path}: {v.name} is no structural parameter of {self.md.modelName}")
        checked = self._checked(values)
        self.calls.configure(variables, checked)
        sizes = {v.valueReference: x for v, x in zip(variables, checked)}
        self.md = Model(self.md.description, structural=sizes)
        self.vars = {v.name: v for v in self.md.modelVariables if v.causality != "independent"}
        self.calls.model = self.md

    def enter_initialization_mode(self, start_time=0.0, tolerance=None):
        """FMI 2.0: setupExperiment and enterInitializationMode; FMI 3.0:
        enterInitializationMode with the start time (and the relative tolerance, if given:
        a Model Exchange instance's integrator's too, artibus.fmu.me)."""
        self.calls.enter_initialization(start_time, tolerance=tolerance)

    def do_step(self, t, h):
        """One step from t to t + h. None, or where the FMU ended the simulation itself
        (artibus.fmu.fmi3: FMI 3.0's terminateSimulation; an FMI 2.0 FMU says so with
        fmi2Discard, an FMICallException, artibus.fmu.result.terminated)."""
        return self.calls.do_step(t, h)

    def last_successful_time(self):
        """where a failed step stopped"""
        return self.calls.last_successful_time()

    def initialize(self, values, start_time=0.0):
        """setupExperiment, the values set in initialisation mode, exit it:
        the instance is ready to step from start_time. Returns self."""
        claim_logger_proxy()
        try:
            self.enter_initialization_mode(start_time)
            self.set_values(values)
            self.calls.exit_initialization()
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
            self.calls.free()
        finally:
            self._remove_dir()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def read_model(path):
    """The Model of the FMU file ``path`` (artibus.fmu.model; its description read once per
    content: _model_description), or an error naming why it cannot be run: not readable, or
    an FMI version other than 2.0 and 3.x."""
    from pathlib import Path
    if not Path(str(path)).is_file():
        raise ArtibusError(f"{path}: no such FMU file")
    try:
        md = _model_description(path)
    except Exception as e:   # not a zip, no or a broken modelDescription.xml, another FMI version
        version = _declared_version(path)
        if version is not None and fmi_major(version) is None:
            raise ArtibusError(f"{path}: says fmiVersion=\"{version}\": artibus runs FMI 2.0 and 3.0 "
                               "FMUs (any 3.x the FMI 3.0 schema allows)") from None
        raise ArtibusError(f"{path}: not a readable FMI 2.0 or 3.0 FMU: {e}") from None
    if fmi_major(md.fmiVersion) is None:
        raise ArtibusError(f"{path}: {md.modelName} says fmiVersion=\"{md.fmiVersion}\": "
                           "artibus runs FMI 2.0 and 3.0 FMUs (any 3.x the FMI 3.0 schema allows)")
    return model_of(md)

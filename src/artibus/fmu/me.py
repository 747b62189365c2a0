"""Model Exchange, one instance (``Calls2``, ``Calls3``): an ME FMU stepped as a Co-Simulation
one by the stepping core's ME facade (src/runner_core/me.c, issue 38), which integrates its
continuous states with SUNDIALS CVODE between two communication points and handles its time,
state and step events with the event iteration (FMI 2.0.4 section 3.2, FMI 3.0 sections 3.2 and 2.3.5).

The instance is FMPy's FMU2Model / FMU3Model (instantiate, the values, the initialisation,
logging: as artibus.fmu.fmi2 / fmi3 do them for Co-Simulation); the facade (``Facade``, an
ac_me of me.h) takes over at fmi2/fmi3ExitInitializationMode (the initial event iteration,
Continuous-Time Mode, CVODE set up) and offers the calls of a Co-Simulation FMU: ``do_step``
here, and to the stepping core its functions' addresses with the facade as the component
(artibus.runner.unit._RawCalls). Relative tolerance: the one given (--relative-tolerance),
else the default experiment's, else DEFAULT_TOLERANCE (FMPy's simulate_fmu takes the same);
absolute: that times each state's nominal value."""
from pathlib import Path
from ctypes import byref, c_double, c_int, c_uint, c_void_p, cast

from fmpy.fmi1 import FMICallException

from artibus.base import ArtibusError
from artibus.fmu import fmi2, fmi3

#: FMPy's relative tolerance in Model Exchange when neither the user nor the FMU gives one
DEFAULT_TOLERANCE = 1e-5
#: a bench's ME units' when neither the user nor the FMU gives one: our plants' CS builds
#: integrate at 1e-6 (their rtol parameter), and their ME builds then give the same KPIs
BENCH_TOLERANCE = 1e-6


def bench_tolerance(model, given=None):
    """A bench's ME unit's relative tolerance: the one given, else its default experiment's,
    else BENCH_TOLERANCE."""
    de = model.defaultExperiment
    if given is not None:
        return given
    return float(de.tolerance) if de is not None and de.tolerance else BENCH_TOLERANCE

_FMI2 = ("SetTime", "SetContinuousStates", "GetContinuousStates", "GetDerivatives", "GetEventIndicators",
         "GetNominalsOfContinuousStates", "CompletedIntegratorStep", "EnterEventMode", "NewDiscreteStates",
         "EnterContinuousTimeMode", "ExitInitializationMode", "GetReal", "SetReal")
_FMI3 = ("SetTime", "SetContinuousStates", "GetContinuousStates", "GetContinuousStateDerivatives",
         "GetEventIndicators", "GetNominalsOfContinuousStates", "CompletedIntegratorStep", "EnterEventMode",
         "UpdateDiscreteStates", "EnterContinuousTimeMode", "ExitInitializationMode", "GetFloat64", "SetFloat64",
         "GetNumberOfContinuousStates", "GetNumberOfEventIndicators", "GetDirectionalDerivative")
_FMI2 += ("GetDirectionalDerivative",)
#: functions an FMU may lack (FMI 3.0's sizes after the structural parameters; the Jacobian's columns)
_OPTIONAL = ("GetNumberOfContinuousStates", "GetNumberOfEventIndicators", "GetDirectionalDerivative")


def _fmi3_provides(unzipped):
    """FMI 3.0's ModelExchange providesDirectionalDerivatives (FMI 3.0 3.3.1), which FMPy 0.3
    reads under FMI 2.0's name only (and so never finds)"""
    from lxml import etree
    if unzipped is None:
        return False
    me = etree.parse(str(Path(unzipped) / "modelDescription.xml")).find("ModelExchange")
    return me is not None and me.get("providesDirectionalDerivatives") == "true"


def me_library():
    """The stepping core's library (the facade is in it), its ME functions' signatures set."""
    from artibus.runner import corelib
    lib, why = corelib.load()
    if lib is None:
        raise ArtibusError(f"Model Exchange needs the C stepping core: {why}")
    if not hasattr(lib, "artibus_me_do_step"):
        raise ArtibusError(f"Model Exchange: {corelib.core_library_path()} is of a build without the ME "
                           "facade (src/runner_core/me.c): build it again")
    if not getattr(lib, "_me_typed", False):
        for name, args, res in (("artibus_me_exit_initialization", [c_void_p], c_int),
                                ("artibus_me_begin_input_event", [c_void_p], c_int),
                                ("artibus_me_end_input_event", [c_void_p], c_int),
                                ("artibus_me_do_step", [c_void_p, c_double, c_double, c_int], c_int),
                                ("artibus_me_free", [c_void_p], None)):
            f = getattr(lib, name)
            f.argtypes, f.restype = args, res
        lib._me_typed = True
    return lib


def _address(lib, name):
    return cast(getattr(lib, name), c_void_p).value


class Facade:
    """One ME FMU's ac_me (me.h): the FMU's functions by name from its own library, the
    solver's settings; ``struct`` the ac_me, ``component`` its address (the stepping core's
    component of the unit), ``functions`` the facade's functions the core calls instead of
    the FMU's doStep/getReal/setReal (and the status and exit functions)."""

    def __init__(self, model, slave, fmi, tolerance, start_time, adams=False):
        from artibus.runner.corelib import struct
        self.lib = me_library()
        self.calls = struct("ac_me_calls")()
        names = _FMI3 if fmi == 3 else _FMI2
        for name in names:
            f = getattr(slave.dll, f"fmi{fmi}{name}", None)
            if f is None and name not in _OPTIONAL:
                raise ArtibusError(f"{model.modelName}: its binary lacks fmi{fmi}{name} (Model Exchange)")
            setattr(self.calls, f"fmi{fmi}{name}", cast(f, c_void_p).value if f is not None else None)
        me = model.modelExchange
        self.unzipped = getattr(slave, "unzipDirectory", None)
        self.struct = s = struct("ac_me")()
        s.component, s.fmi, s.calls = slave.component, fmi, cast(byref(self.calls), c_void_p).value
        s.adams, s.rtol, s.time = int(bool(adams)), tolerance, start_time
        s.completed_step = int(bool(getattr(me, "needsCompletedIntegratorStep", True)))
        s.stop_at_points = 1                  # (free_running: an FMU whose inputs never change)
        s.nx = model.numberOfContinuousStates or 0
        s.nz = model.numberOfEventIndicators or 0
        self._jacobian(model, fmi)
        self.component = cast(byref(s), c_void_p).value
        lib = self.lib
        if fmi == 3:
            self.functions = {"doStep3": _address(lib, "artibus_me3_do_step"),
                              "getFloat64": _address(lib, "artibus_me3_get_float64"),
                              "setFloat64": _address(lib, "artibus_me3_set_float64")}
        else:
            self.functions = {"doStep": _address(lib, "artibus_me_do_step"),
                              "getReal": _address(lib, "artibus_me_get_real"),
                              "setReal": _address(lib, "artibus_me_set_real"),
                              "getBooleanStatus": _address(lib, "artibus_me_get_boolean_status"),
                              "getRealStatus": _address(lib, "artibus_me_get_real_status")}
        self.exit_function = _address(lib, "artibus_me_exit_initialization")

    def _jacobian(self, model, fmi):
        """CVODE's Jacobian from the FMU's directional derivatives (me.c's jac) where it provides
        them (providesDirectionalDerivative: FMI 2.0.4 3.3.1; providesDirectionalDerivatives: FMI 3.0
        3.3.1) and names each derivative's state (its ``derivative`` attribute, scalars, as many as
        numberOfContinuousStates); else CVODE's difference quotients, as before."""
        me, s = model.modelExchange, self.struct
        self.jacobian_available = False
        provides = getattr(me, "providesDirectionalDerivative", False) or (fmi == 3 and _fmi3_provides(self.unzipped))
        ders = [d.variable for d in model.derivatives]
        states = [getattr(v, "derivative", None) for v in ders]
        if (not provides or not ders or len(ders) != s.nx or getattr(self.calls, f"fmi{fmi}GetDirectionalDerivative") is None
                or any(x is None or x.causality == "independent" or getattr(x, "dimensions", None)
                       or getattr(v, "dimensions", None) for x, v in zip(states, ders))):
            return
        self._vrs = ((c_uint * len(ders))(*[x.valueReference for x in states]),
                     (c_uint * len(ders))(*[v.valueReference for v in ders]))
        s.x_vrs, s.dx_vrs = (cast(a, c_void_p).value for a in self._vrs)
        self.jacobian_available = True

    def use_jacobian(self, on=True):
        """CVODE's Jacobian from the FMU's directional derivatives (where it provides them) instead
        of CVODE's difference quotients; before the initialisation's end, where CVODE is set up
        (run/simulate --me-jacobian). Our plants give every column from one forward pass on vector
        dual numbers (BusDynamics: dyn_eval_jacobian), cheaper than the right-hand sides the
        difference quotients take; Bus36m_Circle's BusDynamics runs 1.02-1.05 x as fast with it
        (benchmarks/suite.py, 7.). Off by default: the default runs repeat earlier ones bit for bit."""
        if on and not self.jacobian_available:
            raise ArtibusError("Model Exchange: this FMU provides no directional derivatives of its "
                               "state derivatives by its states (providesDirectionalDerivative)")
        self.struct.jacobian = int(bool(on))

    def use_method(self, method):
        """CVODE's linear multistep method: "bdf" (backward differentiation, for stiff models:
        the default) or "adams" (Adams-Moulton, fewer steps on a non-stiff one); before the
        initialisation's end, where CVODE is set up."""
        if method not in ("bdf", "adams"):
            raise ArtibusError(f"Model Exchange method '{method}': expected bdf or adams")
        self.struct.adams = int(method == "adams")

    def free_running(self):
        """No input will change: CVODE may step beyond a communication point and interpolate back
        (fewer steps; FMPy's simulate_fmu integrates so), instead of stopping at each."""
        self.struct.stop_at_points = 0

    def message(self):
        """why the facade's last call failed (its own words: the FMU's call, CVODE's flag, the time)"""
        return self.struct.message.decode(errors="replace")

    def counts(self):
        """CVODE's steps and right-hand sides, the events by kind, CVODE's restarts"""
        s = self.struct
        return {"steps": s.steps, "rhs": s.rhs_calls, "time_events": s.time_events,
                "state_events": s.state_events, "step_events": s.step_events, "restarts": s.restarts}

    def free(self):
        self.lib.artibus_me_free(byref(self.struct))


class _Me:
    """What the two versions' ME instances share: the facade, set up at
    enter_initialization and working from exit_initialization on."""
    interface = "ModelExchange"

    def _made(self):
        """The facade of the instance just made (its functions' addresses known from now on:
        the stepping core's structs are built before the initialisation)."""
        self.facade = Facade(self.model, self.slave, self.fmi, DEFAULT_TOLERANCE, 0.0, adams=self.adams)

    def _enter(self, start_time, tolerance):
        """The start time and the relative tolerance: given, else the default experiment's,
        else DEFAULT_TOLERANCE."""
        de = self.model.defaultExperiment
        if tolerance is None:
            tolerance = float(de.tolerance) if de is not None and de.tolerance else DEFAULT_TOLERANCE
        self.facade.struct.rtol, self.facade.struct.time = tolerance, start_time

    def exit_initialization(self):
        """fmi2/fmi3ExitInitializationMode by the facade, which goes on with the initial event
        iteration into Continuous-Time Mode and sets CVODE up (FMI 2.0.4 3.2.2, FMI 3.0 2.3.5 "State: Event Mode")."""
        status = self.facade.lib.artibus_me_exit_initialization(self.facade.component)
        if status > 1:
            self._failed("ExitInitializationMode", status)
        self.mode = "step"

    def set(self, variables, values):
        """Set the variables' values. After the initialisation a discrete input is set in
        Event Mode only (FMI 3.0 3.2.1, "State: Continuous-Time Mode": there only the
        continuous-time inputs; FMI 2.0.4 3.2.3, the table of calls): the continuous ones
        are set as they come, the discrete ones whose value changed in an event of their own
        (the facade's input event: Event Mode, the event iteration, CVODE restarted), as
        FMPy's simulate_fmu sets them at its input events; an unchanged one is not set again."""
        held = self.__dict__.setdefault("_held", {})
        if not self.facade.struct.solver:    # (before the initialisation's end, the facade's or the core's: any input)
            super().set(variables, values)
            held.update((v.valueReference, x) for v, x in zip(variables, values) if not _continuous(v))
            return
        pairs = list(zip(variables, values))
        cont = [(v, x) for v, x in pairs if _continuous(v)]
        changed = [(v, x) for v, x in pairs if not _continuous(v) and held.get(v.valueReference, _NONE) != x]
        if cont:
            super().set(*zip(*cont))
        if changed:
            lib, me = self.facade.lib, self.facade.component
            status = lib.artibus_me_begin_input_event(me)
            if status > 1:
                self._failed("EnterEventMode", status)
            super().set(*zip(*changed))
            status = lib.artibus_me_end_input_event(me)
            if status > 1:
                self._failed("UpdateDiscreteStates" if self.fmi == 3 else "NewDiscreteStates", status)
            held.update((v.valueReference, x) for v, x in changed)

    def do_step(self, t, h):
        """Integrate from t to t + h: None, or the time where the FMU ended the simulation
        (terminateSimulation at an event); a failure raises FMICallException, the facade's
        message in the log."""
        status = self.facade.lib.artibus_me_do_step(self.facade.component, t, h, 1)
        if status == 2 and self.facade.struct.terminated:
            return self.facade.struct.last_successful_time
        if status > 1:
            self._failed("DoStep", status)
        return None

    def _failed(self, what, status):
        self.log.append(f"[Error] artibus Model Exchange: {self.facade.message()}")
        raise FMICallException(function=f"fmi{self.fmi}{what} (Model Exchange)", status=status)

    def last_successful_time(self):
        """where the integration stopped"""
        s = self.facade.struct
        return s.last_successful_time if s.terminated else s.time

    def explain(self):
        """The facade's message added to the log after the stepping core's step failed."""
        if self.facade is not None and self.facade.message():
            self.log.append(f"[Error] artibus Model Exchange: {self.facade.message()}")

    def free(self):
        try:
            if self.facade is not None:
                self.facade.free()
        finally:
            super().free()


_NONE = object()                 # (no value held yet)


def _continuous(v):
    """A continuous-time variable (a Real one of variability continuous, FMI 3.0 2.4.7.4's
    default for Float64/Float32; FMI 2.0.4 2.2.7's for Real): settable in Continuous-Time Mode."""
    return v.kind == "Real" and (v.variability or "continuous") == "continuous"


class Calls2(_Me, fmi2.Calls):
    """The FMI 2.0 Model Exchange instance (``slave``: FMPy's FMU2Model)."""

    def __init__(self, model, unzip_dir, instance_name, adams=False):
        from fmpy.fmi2 import FMU2Model
        self.model, self.adams, self.facade, self.log = model, adams, None, None
        self.slave = FMU2Model(guid=model.guid, unzipDirectory=unzip_dir,
                               modelIdentifier=model.modelExchange.modelIdentifier, instanceName=instance_name)
        self._callbacks = None

    def instantiate(self, log, logging=False):
        self.log = log
        super().instantiate(log, logging)
        self._made()

    def enter_initialization(self, start_time=0.0, tolerance=None, stop_time=None):
        super().enter_initialization(start_time, tolerance, stop_time)
        self._enter(start_time, tolerance)


class Calls3(_Me, fmi3.Calls):
    """The FMI 3.0 Model Exchange instance (``slave``: FMPy's FMU3Model)."""

    def __init__(self, model, unzip_dir, instance_name, adams=False):
        from fmpy.fmi3 import FMU3Model
        import math
        self.model, self.name, self.adams, self.facade, self.log = model, instance_name, adams, None, None
        self.slave = FMU3Model(guid=model.instantiationToken, unzipDirectory=unzip_dir,
                               modelIdentifier=model.modelExchange.modelIdentifier, instanceName=instance_name)
        self.event_mode_used = False
        self.messages = []
        self.mode, self.need, self.next_event, self.n_events = "init", False, math.inf, 0

    def instantiate(self, log, logging=False, event_mode=False):
        self.log = log
        self._logger = fmi3.logger(log, self.messages)
        self.slave.instantiate(loggingOn=logging, logMessage=self._logger)
        self._made()

    def enter_initialization(self, start_time=0.0, tolerance=None, stop_time=None):
        super().enter_initialization(start_time, tolerance, stop_time)
        self._enter(start_time, tolerance)


def calls(model, unzip_dir, instance_name, adams=False):
    """The ME instance of the model's FMI version."""
    return (Calls3 if model.fmi == 3 else Calls2)(model, unzip_dir, instance_name, adams=adams)


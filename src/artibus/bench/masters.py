"""What other SSP masters make of our portable packs, as measured (issue 40).

Each SSP 1.0 bench and variant's portable pack (artibus.bench.portable) was run in ecos
(ecospy 0.7.2), libcosim (libcosimpy 0.0.6) and FMPy 0.3.32's ``fmpy.ssp.simulate_ssp``, and
the bench's KPIs (its bench.py) compared with our runner's on the same pack, stepped as that
master steps (tests/test_masters.py: ``STEPPING`` and the tolerance each master earns,
``TOLERANCE``). ``MEASURED`` holds each pack and master where the KPIs are outside that
tolerance or the master does not run the pack: what differs, with the measured figures.
``artibus pack --portable`` prints them as warnings, ``artibus check`` lists them: no pack
runs silently wrong in another master. tests/test_masters.py holds every entry to what it
says (each a strict xfail of the comparison) and every other pack to the tolerance.
"""
from dataclasses import dataclass

#: the masters measured, as tests/masters_run.py names them
MASTERS = ("ecos", "libcosim", "fmpy-ssp")
#: each master's KPI tolerance, relative to ours (absolute floors for KPIs near 0 in
#: tests/test_masters.py, scaled with it), against our runner stepped as the master steps
TOLERANCE = {"libcosim": 2e-3, "ecos": 0.03, "fmpy-ssp": 0.02}


@dataclass(frozen=True)
class Difference:
    """A master's run of a portable pack outside its TOLERANCE: ``what`` differs (measured)."""
    master: str
    what: str

    def text(self):
        return f"in {self.master}: {self.what}"


_ECOS = ("ecos steps the components one after the other in the order of their names, each from the others' "
         "latest outputs (Gauss-Seidel in another order than ours, the connections' feedthrough's): the paths "
         "agree within 3 %, the hinges' lateral force peaks (a few kN of transients) do not: ")
_FMPY_ZERO = ("fmpy.ssp exchanges nothing before the first step, which runs with every input at 0 (no drive force, "
              "straight wheels): ")
_FMPY_UNCONNECTED = ("fmpy.ssp wires an input no connection reaches to the source of the input listed before it "
                     "(fmpy/ssp/ssd.py get_connections keeps that one's start_p), or fails when there is none: ")
_JACKKNIFE = "the bus jack-knifes driving backwards (ours: articulation peaks 56 deg and 35 deg): "

#: (bench, variants) -> [Difference], as measured (2026-12-07, tests/test_masters.py; ours stepped as the master)
MEASURED = {
    ("Bus36m_Circle_Backwards", ()): [
        Difference("ecos", _JACKKNIFE + "158 deg and 161 deg, A6's lateral error 13.0 m (ours 0.04 m), swept path "
                           "28.6 m wide (ours 5.85 m)"),
        Difference("fmpy-ssp", _JACKKNIFE + "74 deg and 119 deg, A3 4.8 m off the A5 trace (ours 0.35 m), hinge "
                               "forces 59 kN and 47 kN (ours 0.76 kN and 0.83 kN)")],
    ("Bus36m_Circle", ("guidedForceMin",)): [
        Difference("ecos", _ECOS + "hinge 1 0.65 kN against our 0.76 kN (-15 %)"),
        Difference("fmpy-ssp", _FMPY_ZERO + "hinge force peaks 2.2 kN and 17.5 kN (ours 0.76 kN and 0.83 kN), A6 "
                               "1.05 m off the A2 trace (ours 0.91 m)")],
    ("Bus36m_Circle", ("guided",)): [
        Difference("fmpy-ssp", _FMPY_ZERO + "articulation peak at hinge 1 36.0 deg (ours 35.2 deg, +2.2 %)")],
    ("Bus36m_Circle", ("guidedAll",)): [
        Difference("fmpy-ssp", _FMPY_ZERO + "A6 1.27 m off the A2 trace on the circle (ours 1.23 m, +3 %)")],
    ("Bus36m_LaneChange", ()): [
        Difference("ecos", _ECOS + "1.61 kN and 1.69 kN against our 1.77 kN and 1.93 kN (-9 %, -12 %)"),
        Difference("fmpy-ssp", _FMPY_ZERO + "hinge-2 force peak 17.5 kN (ours 1.9 kN), lateral acceleration 4.5 "
                               "m/s2 (ours 1.8 m/s2), A6's overshoot 0.020 m (ours 0.048 m)")],
    ("Bus36m_Slalom", ()): [
        Difference("ecos", _ECOS + "1.45 kN and 1.49 kN against our 1.63 kN and 1.77 kN (-11 %, -16 %)"),
        Difference("fmpy-ssp", "does not run: fmpy.ssp sets no String parameter, so the Driver has no road file "
                               "(fmi2ExitInitializationMode fails)")],
    ("MultiAxle_StepSteer", ()): [
        Difference("fmpy-ssp", _FMPY_UNCONNECTED + "the step steer Steering.delta1 is fed Steering.delta[3] (0), "
                               "nothing steers: yaw-rate gain 0 (ours 1.39 1/s)")],
    ("Scania18m_Damping", ("baseline",)): [
        Difference("fmpy-ssp", _FMPY_ZERO + "the baseline's damping request dips to 3.5 % (ours at least 13.4 %)")],
    ("Scania18m_OpenLoop", ()): [
        Difference("fmpy-ssp", "does not run: " + _FMPY_UNCONNECTED + "the free input Bus.delta[1] is the first "
                               "(UnboundLocalError)")],
    ("Urbino18_Replay", ()): [
        Difference("fmpy-ssp", "does not run: " + _FMPY_UNCONNECTED + "the replay's free inputs come first "
                               "(UnboundLocalError)")],
    ("Urbino18_Replay", ("prediction",)): [
        Difference("fmpy-ssp", "does not run: " + _FMPY_UNCONNECTED + "the replay's free inputs come first "
                               "(UnboundLocalError)")],
}


def differences(bench, variants=()):
    """[Difference] of the bench (its name) with the variants, as measured."""
    return list(MEASURED.get((bench, tuple(variants or ())), ()))


def all_differences(bench):
    """[(variants, Difference)] of the bench and every variant of it (``artibus check``)."""
    return [(v, d) for (b, v), ds in MEASURED.items() if b == bench for d in ds]

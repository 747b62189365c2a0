"""Seed 001's damping study, its definitions: the bench, the damping functions
the thesis compares (the bench's variants) with their labels and gains, the
driving cases and the study's thresholds (artibus.study.damping runs them)."""
import math
from dataclasses import dataclass

from artibus.base import ROOT

BENCH = "Scania18m_Damping"
DEG = 180 / math.pi

#: the damping functions the thesis compares (variants of the bench)
FUNCTIONS = ("none", "floor", "baseline", "option1", "option2", "option3", "revised")
LABELS = {"none": "no damping", "floor": "3.5 % floor only", "baseline": "baseline (ACS5-like)",
          "option1": "option 1 (angle)", "option2": "option 2 (rate)", "option3": "option 3 (both)",
          "revised": "revised (6.1.3)"}
#: which gain of DampingGains.ssv each option's calibration sets (thesis Table 5.3)
GAINS = {"option1": "K1", "option2": "K2", "option3": "K3", "revised": "Krev"}
THESIS_GAINS = {"K1": 0.130, "K2": 0.565, "K3": 0.605, "Krev": None}


@dataclass(frozen=True)
class Case:
    length: float       # lane change length, m
    speed_kmh: float
    mu_rear: float


#: the driving cases (variants of the bench): seed 001, 4.2, 5.2.1, 5.2.2, 5.2.5
CASES = {"lc25_50": Case(25.0, 50.0, 1.0), "lc60_100": Case(60.0, 100.0, 0.2),
         "lc200_100": Case(200.0, 100.0, 0.2), "lc60_130": Case(60.0, 130.0, 0.2)}
ROAD_BEFORE = 25.0      # RoadFollowDriver.roadBefore (its default): straight before the lane change
OFFSET = 3.25           # lane offset, m (seed 001, 4.2)
TARGET_PCT = 13.5       # the calibration's peak damping (seed 001, 5.2.2: ACS5's ground level at 100 km/h)
SETTLED_DEG = 1.0       # the articulation oscillation has settled below this, deg
OSCILLATION_DEG = 0.5   # an extremum of the articulation angle above this counts as an oscillation, deg
GAINS_FILE = ROOT / "ssp" / "parameters" / "DampingGains.ssv"

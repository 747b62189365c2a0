"""CAN in the loop: the DBC, the network of a run, its codec and E2E checks,
faults, logs, and the replay of recorded logs (``artibus.can.replay``)."""
from artibus.can.network import *   # noqa: F401,F403

"""``--can-fault`` on an FMI-LS-BUS bench (artibus.runner.lsbus_bench): the faults the bus
simulation FMU CanBus injects itself, as its fault parameters (modelDescription/fmi3/CanBus.xml:
faultStart, faultSilentNode, faultCorruptId, faultBusOffNode), from the text form of the CAN
benches' faults (artibus.can.faults.parse_fault).

What CanBus does, and so what an LS-BUS bench takes:

- ``silent:NODE@T0``: the node's frames never reach the bus from T0;
- ``busoff:NODE@T0``: the node is bus-off from T0 (its frames dropped, it receives none), for
  good: no ``recover``;
- ``corrupt:MESSAGE[:crc]@T0``: every frame of the message is a CRC Bus Error to every node
  from T0 (rate 1).

NODE is one of the bench's LS-BUS nodes (its component name: ``ECU2``), or the DBC's name of
an ECU, which is one node: ``TractorECU`` the SteeringECU_LSBUS node of module 1,
``ModuleKECU`` of module K. The DBC is the one the nodes' frame codec is generated from
(ssp/can/Bus36m.dbc, src/artibus/can/gen_c.py). One start time for every fault (CanBus has
one faultStart), at most one fault of each kind, no end of the window. Anything else (loss,
latency, a rate, repeat/skip, a window's end, a sensor of the four in the one Sensors node) is
refused, saying what CanBus can do instead."""
import math
import re

from artibus.base import ROOT, ArtibusError

#: the DBC the LS-BUS nodes' frame codec is generated from
NODES_DBC = ROOT / "ssp" / "can" / "Bus36m.dbc"
#: the fault kind -> CanBus's parameter
PARAMETER = {"silent": "faultSilentNode", "busoff": "faultBusOffNode", "corrupt": "faultCorruptId"}


def _node_index(target, nodes, head):
    """the CanBus terminal (1..n) of the node named by target: a node component of the bench, or
    the DBC's ECU of module k (TractorECU: 1, ModuleKECU: K) when one node is that ECU"""
    names = list(nodes)
    if target in nodes:
        return names.index(target) + 1
    m = re.fullmatch(r"TractorECU|Module([0-9]+)ECU", target)
    if m:
        module = int(m.group(1) or 1)
        ecus = [n for n, (path, params) in nodes.items()
                if path.stem.startswith("SteeringECU") and int(params.get("module", 1)) == module]
        if len(ecus) == 1:
            return names.index(ecus[0]) + 1
    sensors = [n for n, (path, _) in nodes.items() if path.stem.startswith("SteeringSensors")]
    also = (f"; the DBC's sensors are all the one node {sensors[0]}: silent:{sensors[0]} silences the four"
            if sensors and "Sensor" in target else "")
    raise ArtibusError(f"{head}: {target} is not a node of the FMI-LS-BUS network (its nodes: "
                       f"{', '.join(names)}; or TractorECU, Module2ECU, Module3ECU){also}")


def _message_id(target, head):
    from artibus.can.dbc import load_dbc
    db = load_dbc(NODES_DBC)
    try:
        return db.get_message_by_name(target).frame_id
    except KeyError:
        raise ArtibusError(f"{head}: {target} is not a message of {NODES_DBC.name} "
                           f"(its messages: {', '.join(m.name for m in db.messages)})") from None


def bus_fault_parameters(faults, nodes, where):
    """{CanBus parameter: value} for the faults (artibus.can.Fault or their text); nodes: the
    bench's {node: (FMU path, parameters)} in the order of CanBus's terminals; where: the bench,
    for messages. ArtibusError naming the fault and what CanBus does otherwise."""
    from artibus.can.faults import Fault, parse_fault
    params, start = {}, None
    for f in faults or ():
        f = f if isinstance(f, Fault) else parse_fault(f)
        head = f"--can-fault {f} on {where} (faults injected by its bus simulation FMU CanBus)"
        if f.kind not in PARAMETER:
            raise ArtibusError(f"{head}: CanBus injects silent, busoff and corrupt (crc) faults, not {f.kind}")
        if f.kind == "corrupt" and (f.mode != "crc" or f.rate != 1.0):
            raise ArtibusError(f"{head}: CanBus corrupts every frame of the message with a CRC error "
                               "(corrupt:MESSAGE:crc, no rate)")
        if f.kind == "busoff" and f.recover is not None:
            raise ArtibusError(f"{head}: a node CanBus puts bus-off stays off (no recover)")
        if math.isfinite(f.end):
            raise ArtibusError(f"{head}: CanBus's faults act from their start to the end of the run (no @T0-T1)")
        t0 = f.start if math.isfinite(f.start) else 0.0
        if start is not None and t0 != start:
            raise ArtibusError(f"{head}: CanBus has one start time for its faults (faultStart), here "
                               f"{start:g} s and {t0:g} s")
        start, name = t0, PARAMETER[f.kind]
        if name in params:
            raise ArtibusError(f"{head}: CanBus injects one {f.kind} fault")
        if f.kind == "corrupt" and not any(path.stem.endswith("_LSBUS") for path, _ in nodes.values()):
            raise ArtibusError(f"{head}: the message names are {NODES_DBC.name}'s, whose codec artibus's LS-BUS "
                               "nodes (*_LSBUS.fmu) carry; this network has none of them")
        params[name] = (_message_id(f.target, head) if f.kind == "corrupt" else
                        _node_index(f.target, nodes, head))
    if params:
        params["faultStart"] = start
    return params

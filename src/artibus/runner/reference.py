"""The monolithic reference of a bench (issue 44): ``artibus run BENCH --reference``,
``Simulation(bench, reference=True)``.

Every component that offers Model Exchange runs as ME (artibus.fmu.me), and those ME units are
integrated together in one CVODE at a tight tolerance (REFERENCE_TOLERANCE) by the stepping
core's ME group (src/runner_core/me_group.c, me.h's ac_me_group): their states and event
indicators concatenated, each member's continuous input that another member's output feeds set
inside every right-hand side (the bench's connection with its linear transformation or unit
factor), their time, state and step events handled for the group. The sampled controllers, the
driver, the ECUs and the CAN network stay as they are, Co-Simulation units at their own periods:
they are discrete by nature. Each member stays a unit of the one stepping loop, with its inputs
from outside the group and its outputs; the first member's step integrates the group, the
others' find it done (the plan writes every member's inputs before it: artibus.runner.plan).

The sampled controllers' timing is the bench's, as the default run's Gauss-Seidel order makes
it (artibus.runner.plan; each bench's README states it): a controller without direct
feedthrough goes before the plants, so at each of its sample instants it reads the plants'
outputs at that instant and its output holds over its period from the base step where its
period ends."""
from ctypes import byref, c_double, c_int, c_void_p, cast

from artibus.base import ArtibusError

#: the reference's relative tolerance (absolute: that times each state's nominal)
REFERENCE_TOLERANCE = 1e-8


def _members(sim):
    """The ME units of a set-up Simulation (their facades made: artibus.fmu.me)."""
    return [u for u in sim.units if getattr(u.fmu.calls, "facade", None) is not None]


def no_members(sim, where):
    """The error of a bench none of whose components offers Model Exchange."""
    parts = ", ".join(f"{u.path} ({u.fmu.md.modelName})" for u in sim.units)
    return ArtibusError(f"{where}: --reference: no component offers Model Exchange (the reference integrates "
                        f"those together; components, all Co-Simulation only: {parts})")


def link_order(links, where):
    """The group's internal connections in evaluation order: a connection after those into its
    source's inputs that its source output depends on (the unit's feedthrough, declared or assumed:
    artibus.runner.plan.feedthrough). A loop of them is an algebraic loop the group cannot
    evaluate: an error naming it."""
    def deps(l2):
        src = l2.src
        out = src.outputs[l2.src_index].name
        return [l1 for l1 in links if l1.dst is src and (l1.dst.inputs[l1.dst_index].name, out) in src.feeds]

    state, ordered, stack = {}, [], []

    def visit(l):
        state[id(l)] = 1
        stack.append(l)
        for d in deps(l):
            if state.get(id(d)) == 1:
                loop = stack[stack.index(d):] + [d]
                raise ArtibusError(f"{where}: --reference: algebraic loop inside the Model Exchange group "
                                   f"(direct feedthrough all around): "
                                   + " -> ".join(f"{x.src.path}.{x.src.outputs[x.src_index].name}" for x in loop)
                                   + f" ({loop[0].name}); the group cannot evaluate it")
            if state.get(id(d)) is None:
                visit(d)
        stack.pop()
        state[id(l)] = 2
        ordered.append(l)

    for l in links:
        if state.get(id(l)) is None:
            visit(l)
    return ordered


class Group:
    """The ac_me_group of a Simulation's ME units (me.h), set up after the Simulation's
    set-up and before its run: the members' steps made one (the shortest of theirs), their
    facades pointed at the group, the connections inside it in evaluation order."""

    def __init__(self, sim, members, where):
        from artibus.runner.corelib import struct
        from artibus.fmu.me import me_library
        self.lib = lib = me_library()
        if not hasattr(lib, "artibus_me_group_step"):
            raise ArtibusError("--reference: the stepping core library is of a build without the Model "
                               "Exchange group (src/runner_core/me_group.c): build it again")
        lib.artibus_me_group_free.argtypes, lib.artibus_me_group_free.restype = [c_void_p], None
        index = {id(u): i for i, u in enumerate(members)}
        inside = [l for l in sim.links if id(l.src) in index and id(l.dst) in index]
        self.links = link_order(inside, where)
        step = min(u.step for u in members)
        for u in members:                    # one step for the group (each member's: its step op)
            u.step, u.ratio, u.group = step, int(round(step / sim.base_step)), self
        link_t = struct("ac_me_link")
        self._links = (link_t * max(1, len(self.links)))()
        for k, l in enumerate(self.links):
            x = self._links[k]
            x.src_member, x.dst_member = index[id(l.src)], index[id(l.dst)]
            x.src_vr, x.dst_vr = l.src.outputs[l.src_index].valueReference, l.dst.inputs[l.dst_index].valueReference
            x.factor, x.offset = l.factor, l.offset
        self._members = (c_void_p * len(members))(*(u.fmu.calls.facade.component for u in members))
        self.struct = g = struct("ac_me_group")()
        g.n_members, g.members = len(members), cast(self._members, c_void_p).value
        g.n_links, g.links = len(self.links), cast(self._links, c_void_p).value
        g.rtol = sim.relative_tolerance
        g.adams = int(sim.me_method == "adams")
        g.fail_member = -1
        self.address = cast(byref(g), c_void_p).value
        for u in members:
            f = u.fmu.calls.facade.struct
            f.group = self.address
            f.name = u.path.encode()[:127]
        self.members = members

    def counts(self):
        """CVODE's steps and right-hand sides, the events by kind, its restarts"""
        g = self.struct
        return {"steps": g.steps, "rhs": g.rhs_calls, "time_events": g.time_events,
                "state_events": g.state_events, "step_events": g.step_events, "restarts": g.restarts}

    def free(self):
        self.lib.artibus_me_group_free(self.address)


def set_up(sim, where):
    """The reference's group of a set-up Simulation (sim.reference true), or an error when no
    component offers Model Exchange. A group of one is that unit's facade alone (at the
    reference's tolerance)."""
    members = _members(sim)
    if not members:
        raise no_members(sim, where)
    return Group(sim, members, where) if len(members) > 1 else None

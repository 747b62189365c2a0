"""Units of the FMUs' variables: a variable's declared unit (its own, else its
declaredType's) and the factor and offset from one variable's unit to
another's, by the model descriptions' unit definitions (base units, factor and
offset). The runner converts connected values with them; the CAN path
(artibus.can) has its own table of the units a signal may carry."""
from dataclasses import dataclass, field

from artibus.base import ArtibusError


def declared_unit(var):
    """A model variable's unit: its own unit=, else its declaredType's, else None."""
    if var.unit:
        return var.unit
    if var.declaredType is not None and getattr(var.declaredType, "unit", None):
        return var.declaredType.unit
    return None


def unit_of(var):
    """A model variable's unit: its own unit=, else its declaredType's, else ""."""
    if getattr(var, "unit", None):
        return var.unit
    declared = getattr(var, "declaredType", None)
    return getattr(declared, "unit", None) or ""


def unit_conversion(md_a, var_a, md_b, var_b, where):
    """factor, offset taking a value in var_a's unit to var_b's unit."""
    ua, ub = declared_unit(var_a), declared_unit(var_b)
    if ua is None or ub is None or ua == ub:
        return 1.0, 0.0
    da = {u.name: u for u in md_a.unitDefinitions}.get(ua)
    db = {u.name: u for u in md_b.unitDefinitions}.get(ub)
    if da is None or db is None or da.baseUnit is None or db.baseUnit is None:
        raise ArtibusError(f"{where}: units '{ua}' and '{ub}' differ and one has no base-unit definition")
    dims = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
    if any(getattr(da.baseUnit, d) != getattr(db.baseUnit, d) for d in dims):
        raise ArtibusError(f"{where}: cannot convert '{ua}' to '{ub}': different dimensions")
    fa, oa = da.baseUnit.factor, da.baseUnit.offset
    fb, ob = db.baseUnit.factor, db.baseUnit.offset
    # base = fa*x + oa ; y = (base - ob) / fb
    return fa / fb, (oa - ob) / fb


# ---- units on parameter values (SSP 1.0: an .ssv's or .ssd's Real value="5128" unit="mm") -----------

#: SSP's and FMI's base units, in the order of their BaseUnit exponents
DIMS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


@dataclass(frozen=True)
class UnitDef:
    """A unit as SSP 1.0 (ssc:Unit/ssc:BaseUnit) and FMI 2.0 (Unit/BaseUnit)
    define it: exponents of the base units, and a value in it is
    factor * value + offset in those base units."""
    name: str
    exponents: tuple
    factor: float = 1.0
    offset: float = 0.0
    origin: str = field(default="", compare=False)    # file:line of its definition ("": the FMU's)

    def dimension(self):
        return ".".join(f"{d}^{e}" if e != 1 else d for d, e in zip(DIMS, self.exponents) if e) or "1"

    def text(self):
        """the unit in the base units, e.g. 0.001 m (mm), 1 K + 273.15 (degC)"""
        return f"{self.factor:g} {self.dimension()}" + (f" + {self.offset:g}" if self.offset else "")


def _exponents(**e):
    return tuple(e.get(d, 0) for d in DIMS)


#: the SI units a parameter file may not give another meaning: the base units and the derived
#: units with special names (SI Brochure, 9th ed., 2.3.3 and 2.3.4, Tables 2 and 4), each
#: factor 1 and offset 0 in the base units (FMI 2.0 2.2.2, SSP 1.0 5.5.1 "Units": a value in
#: the unit is factor * value + offset in the base units); rad also as a plain 1 (the SI
#: Brochure's radian is m/m: FMI lets a tool count it or not)
SI_UNITS = {
    "kg": (_exponents(kg=1),), "m": (_exponents(m=1),), "s": (_exponents(s=1),), "A": (_exponents(A=1),),
    "K": (_exponents(K=1),), "mol": (_exponents(mol=1),), "cd": (_exponents(cd=1),),
    "rad": (_exponents(rad=1), _exponents()),
    "N": (_exponents(kg=1, m=1, s=-2),), "Pa": (_exponents(kg=1, m=-1, s=-2),),
    "J": (_exponents(kg=1, m=2, s=-2),), "W": (_exponents(kg=1, m=2, s=-3),), "Hz": (_exponents(s=-1),),
    "C": (_exponents(s=1, A=1),), "V": (_exponents(kg=1, m=2, s=-3, A=-1),),
}


def _unit_def(u, where):
    """the UnitDef of one ssc:Unit element, checked against SI_UNITS for an SI unit's name"""
    bu = next((b for b in u if isinstance(b.tag, str) and b.tag.rpartition("}")[2] == "BaseUnit"), None)
    a = {} if bu is None else bu.attrib
    head = f"{where}:{u.sourceline}: <Unit name=\"{u.get('name')}\">"
    try:
        d = UnitDef(u.get("name"), tuple(int(a.get(k, 0)) for k in DIMS),
                    float(a.get("factor", 1.0)), float(a.get("offset", 0.0)), f"{where}:{u.sourceline}")
    except ValueError:
        raise ArtibusError(f"{head}: its BaseUnit's exponents, factor and offset must be numbers") from None
    si = SI_UNITS.get(d.name)
    if si is not None and (d.exponents not in si or (d.factor, d.offset) != (1.0, 0.0)):
        want = UnitDef(d.name, si[0])
        raise ArtibusError(f"{head}: defined as {d.text()}, but {d.name} is the SI unit {want.text()}; "
                           f"a file may not redefine an SI unit (give the value in {d.name}, or define the "
                           "unit under a name of its own)")
    return d


def ssp_units(element, where=""):
    """{name: UnitDef} of the ssc:Unit elements in ``element``'s Units child
    (an ssv:ParameterSet or the ssd:SystemStructureDescription). A name defined
    twice in the one Units (the last would win: 6100 mm read as 6100 m) or an
    SI unit's name given another meaning (SI_UNITS) is an error naming the file
    and the line."""
    out = {}
    for child in element:
        if not isinstance(child.tag, str) or child.tag.rpartition("}")[2] != "Units":
            continue
        for u in child:
            if not isinstance(u.tag, str) or u.tag.rpartition("}")[2] != "Unit":
                continue
            d = _unit_def(u, where)
            if d.name in out:
                raise ArtibusError(f"{where}:{u.sourceline}: <Unit name=\"{d.name}\">: defined twice in one "
                                   f"<Units> (first at line {out[d.name].origin.rpartition(':')[2]} as "
                                   f"{out[d.name].text()}, here as {d.text()}); a unit has one definition")
            out[d.name] = d
    return out


def unit_table(used, fmu_defs=None):
    """the lines of a short table of the units a file uses: ``used`` {unit name: its
    UnitDef or None}, each with its factor and offset to the SI base units and where it is
    defined (its file and line, the FMU, or nowhere)"""
    rows = [("unit", "factor", "offset", "base units", "defined")]
    for name in sorted(used):
        d = used[name] or (fmu_defs or {}).get(name)
        if d is None:
            rows.append((name, "?", "?", "?", "nowhere (an unknown unit)"))
            continue
        rows.append((name, f"{d.factor:.10g}", f"{d.offset:.10g}", d.dimension(), d.origin or "the FMU"))
    widths = [max(len(r[k]) for r in rows) for k in range(4)]
    return ["  ".join(c.ljust(w) for c, w in zip(r[:4], widths)) + "  " + r[4] for r in rows]


def fmu_units(md):
    """{name: UnitDef} of a model description's UnitDefinitions (FMPy's), their
    DisplayUnits too (FMI 2.0: display value = factor * value + offset); a unit
    without a BaseUnit is left out (it converts to nothing but itself)."""
    out = {}
    for u in getattr(md, "unitDefinitions", None) or []:
        b = u.baseUnit
        if b is None:
            continue
        base = UnitDef(u.name, tuple(int(getattr(b, d, 0) or 0) for d in DIMS), float(b.factor), float(b.offset))
        out[u.name] = base
        for d in getattr(u, "displayUnits", None) or []:
            f, o = float(d.factor), float(d.offset)
            # x [display] = f * y [unit] + o  ->  y = (x - o) / f, in base: base.factor * y + base.offset
            out.setdefault(d.name, UnitDef(d.name, base.exponents, base.factor / f,
                                           base.offset - base.factor * o / f))
    return out


def to_unit(value, unit, definitions, target, target_definitions, label):
    """``value`` given in ``unit`` as a value in ``target`` (the FMU variable's
    unit): unchanged where the two are the same unit, else through their
    definitions (``definitions``: the parameter file's own Units, then
    ``target_definitions``: the FMU's UnitDefinitions). ``label`` names the
    file and the parameter for the error of an unknown unit or one of another
    dimension."""
    src = definitions.get(unit) or target_definitions.get(unit)
    if unit == target and (src is None or src == target_definitions.get(target, src)):
        return value
    if target is None:
        if src is not None and not any(src.exponents) and (src.factor, src.offset) == (1.0, 0.0) or unit == "1":
            return value
        raise ArtibusError(f"{label}: unit '{unit}': the FMU's variable declares no unit to convert it to")
    if src is None:
        raise ArtibusError(f"{label}: unknown unit '{unit}' (the variable's unit is '{target}'): define it in the "
                           f"parameter file's <Units> (<ssc:Unit name=\"{unit}\"><ssc:BaseUnit ... factor=\"...\"/>"
                           f"</ssc:Unit>) or give the value in '{target}'")
    dst = target_definitions.get(target)
    if dst is None:
        raise ArtibusError(f"{label}: unit '{unit}' cannot be converted to '{target}': the FMU defines no base "
                           f"units for '{target}'")
    if src.exponents != dst.exponents:
        raise ArtibusError(f"{label}: unit '{unit}' ({src.dimension()}) cannot be converted to the variable's "
                           f"unit '{target}' ({dst.dimension()}): another dimension")
    return (src.factor * value + src.offset - dst.offset) / dst.factor


def with_unit(raw, unit, definitions, var, md, label):
    """``raw`` given in ``unit`` (``definitions``: the file's own units) as a value in the unit
    of the model variable ``var`` of ``md``; ``label`` names the file, the line and the
    parameter. A unit on a variable that is not a Real is an error; an unknown variable is
    left to the binding's check (artibus.bench.parameters.check_against names it)."""
    if var is None:
        return raw
    if var.kind != "Real":
        raise ArtibusError(f"{label}: a value with a unit ('{unit}') for {md.modelName}.{var.name}, an {var.type}: "
                           "a unit belongs to a Real value (give the value without a unit)")
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        return raw                        # check_against says what it is
    return to_unit(float(raw), unit, definitions, declared_unit(var), fmu_units(md), label)


@dataclass(frozen=True)
class Quantity:
    """A Real value with the unit a parameter file gives it, not yet in the
    unit of the variable it sets (``artibus run --ssv FILE``: the runner
    converts it, ``convert``)."""
    value: float
    unit: str
    definitions: dict
    origin: str

    def __str__(self):
        return f"{self.value!r} {self.unit}"

    def __hash__(self):
        return hash((self.value, self.unit, self.origin))


def convert(q, var, md, name):
    """A Quantity as a value of the model variable ``var`` of ``md``, in its unit."""
    return to_unit(q.value, q.unit, q.definitions, declared_unit(var), fmu_units(md),
                   f"{q.origin}: Parameter '{name}' = {q.value!r} {q.unit}")

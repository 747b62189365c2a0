"""Units of the FMUs' variables: a variable's declared unit (its own, else its
declaredType's) and the factor and offset from one variable's unit to
another's, by the model descriptions' unit definitions (base units, factor and
offset). The runner converts connected values with them; the CAN path
(artibus.can) has its own table of the units a signal may carry."""
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

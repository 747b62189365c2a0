"""``--set`` over arrays: ``Bus.mu[*]=0.5`` sets every element of ``mu``,
``Bus.mu[1:6]=0.5`` elements 1 to 6 (inclusive, 1-based, as the FMUs name
them: ``mu[1]`` .. ``mu[6]``)."""
import re

from artibus.base import ArtibusError

_RANGE = re.compile(r"^(?P<base>.+)\[(?P<sel>\*|\s*-?\d+\s*:\s*-?\d+\s*)\]$")
_ELEMENT = re.compile(r"^(?P<base>.+)\[(?P<i>-?\d+)\]$")


def elements(base, names):
    """{index: name} of the array ``base`` among the variable ``names``."""
    out = {}
    for n in names:
        m = _ELEMENT.match(n)
        if m and m["base"] == base:
            out[int(m["i"])] = n
    return out


def expand(name, value, names, what="--set", label=None):
    """[(name, value)]: ``name`` itself, or the elements of ``base[*]`` /
    ``base[a:b]`` among ``names`` (the variables of the FMU it is set on).
    ArtibusError naming the valid range when ``a:b`` leaves it."""
    m = _RANGE.match(name)
    if not m:
        return [(name, value)]
    base, sel = m["base"], m["sel"].strip()
    name = label or name
    shown = name[:name.index("[")]                 # Bus.mu
    have = elements(base, names)
    if not have:
        raise ArtibusError(f"{what} {name}={value}: '{base}' is not an array variable (no {base}[1])")
    lo, hi = min(have), max(have)
    if sel == "*":
        return [(have[i], value) for i in sorted(have)]
    a, b = (int(x) for x in sel.split(":"))
    if a > b:
        raise ArtibusError(f"{what} {name}={value}: empty range {a}:{b} (give FIRST:LAST, inclusive)")
    if a < lo or b > hi or any(i not in have for i in range(a, b + 1)):
        raise ArtibusError(f"{what} {name}={value}: {shown} has elements {lo}..{hi} "
                           f"(valid: {shown}[{lo}:{hi}] or a range within it, or {shown}[*])")
    return [(have[i], value) for i in range(a, b + 1)]


def expand_all(values, names_of, what="--set"):
    """{full name: value} with every array selection expanded. names_of(prefix)
    gives the variable names the name (after the prefix) is looked up in, and
    the prefix: a function full_name -> (prefix, names) or None (left as is)."""
    out = {}
    for full, value in values.items():
        if "[" not in full or not full.rstrip().endswith("]") or not _RANGE.match(full):
            out[full] = value
            continue
        found = names_of(full)
        if found is None:
            out[full] = value
            continue
        prefix, names = found
        for n, v in expand(full[len(prefix):], value, names, what, label=full):
            out[prefix + n] = v
    return out

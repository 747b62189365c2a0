#!/usr/bin/env python3
"""Generate a model's C variable table from its modelDescription.xml.

The XML is the single source of truth for every variable: name, value
reference, type, causality, variability, start value and range. This script
turns it into

  <out>/model_vars.h  the ModelData struct (one field per variable, arrays for
                      structured names such as ``L[1]``), VR_* constants,
                      MODEL_IDENTIFIER and MODEL_GUID;
  <out>/model_vars.c  the table VARS[] (value reference -> field offset, type,
                      causality, variability, range), the list REAL_OUTPUTS[],
                      per-type look-up arrays and vars_set_start_values().

An Enumeration variable (declaredType= a <SimpleType><Enumeration>) is an int field, its
range (the layer's range check) the smallest to the largest of its items, which must be
consecutive; its start value must be one of them.

A model description with <ModelExchange> (a plant) also gets MODEL_NX (its
continuous states, in the order of <ModelStructure><Derivatives>), MODEL_NZ
(event indicators), X_NAME[] and X_NOMINAL[]; a derivative named der(x) or
der(x[i]) becomes the field der_x (der_x[i]).

Array fields are sized max index + 1 so that C code indexes them exactly as the
paper does (``d->L[i]`` for i = 1..N, ``d->theta[i]`` for i = 0..N).

With --fmi 3 the table is the FMI 3.0 build's: the value references are FMI 3.0's
(fmi3_value_references: one space for all types), an Enumeration is read and written
as Int64 (T_ENUMERATION), and MODEL_VR_TIME (the independent variable time) and
MODEL_VR_Z0 (the first of the MODEL_NZ event indicators, which FMI 3.0 declares as
variables) are defined. src/fmi/package_fmu.py writes the FMI 3.0 model description
with the same value references.

Only the Python standard library is used: this runs inside the CMake build.

usage: gen_vars.py modelDescription.xml OUTDIR [--fmi 3]
"""

import math
import os
import re
import sys
import xml.etree.ElementTree as ET

C_TYPE = {"Real": "double", "Integer": "int", "Enumeration": "int",
          "Boolean": "int", "String": "char"}
TYPE_ENUM = {"Real": "T_REAL", "Integer": "T_INTEGER", "Enumeration": "T_INTEGER",
             "Boolean": "T_BOOLEAN", "String": "T_STRING"}
TYPES = ("T_REAL", "T_INTEGER", "T_BOOLEAN", "T_STRING", "T_ENUMERATION")
NAME_RE = re.compile(r"^([A-Za-z_][A-Za-z0-9_.]*)(?:\[(\d+)\])?$")
# a derivative in the structured convention, der(NAME) or der(NAME[i]): field der_NAME
DER_RE = re.compile(r"^der\(([A-Za-z_][A-Za-z0-9_.]*)(?:\[(\d+)\])?\)$")


class ModelDescriptionError(Exception):
    pass


def c_ident(base):
    return base.replace(".", "_")


def c_double(text):
    value = float(text)
    if math.isinf(value):
        return "INFINITY" if value > 0 else "-INFINITY"
    return repr(value)


def c_string(text):
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def read(xml_path):
    root = ET.parse(xml_path).getroot()
    cs = root.find("CoSimulation")
    if cs is None:
        raise ModelDescriptionError(f"{xml_path}: no <CoSimulation> element")
    model = {"identifier": cs.get("modelIdentifier"), "guid": root.get("guid"),
             "vars": []}
    seen = {}
    items = enumeration_items(root, xml_path)
    for sv in root.find("ModelVariables").findall("ScalarVariable"):
        name = sv.get("name")
        m = NAME_RE.match(name) or DER_RE.match(name)
        if not m:
            raise ModelDescriptionError(
                f"{xml_path}: ScalarVariable name '{name}' is not NAME or NAME[i]")
        typ_el = next(iter(sv))
        typ = typ_el.tag
        vr = int(sv.get("valueReference"))
        key = (TYPE_ENUM[typ], vr)
        if key in seen:
            raise ModelDescriptionError(
                f"{xml_path}: valueReference {vr} of '{name}' already used by '{seen[key]}'")
        seen[key] = name
        causality = sv.get("causality", "local")
        variability = sv.get("variability", "continuous")
        start = typ_el.get("start")
        lo, hi = typ_el.get("min"), typ_el.get("max")
        if typ == "Enumeration":
            values = items.get(typ_el.get("declaredType"))
            if values is None:
                raise ModelDescriptionError(f"{xml_path}: Enumeration '{name}': declaredType "
                                            f"'{typ_el.get('declaredType')}' is no <SimpleType><Enumeration>")
            # its range is its items' (the variable needs no min/max of its own)
            lo, hi = lo or str(min(values)), hi or str(max(values))
            if start is not None and int(start) not in values:
                raise ModelDescriptionError(f"{xml_path}: Enumeration '{name}': start {start} is no item "
                                            f"of {typ_el.get('declaredType')}")
        if start is None and causality in ("parameter", "input"):
            raise ModelDescriptionError(f"{xml_path}: {causality} '{name}' has no start value")
        model["vars"].append({
            "name": name,
            "base": ("der_" if name.startswith("der(") else "") + c_ident(m.group(1)),
            "index": int(m.group(2)) if m.group(2) is not None else None,
            "type": typ, "vr": vr, "causality": causality, "variability": variability,
            "start": start, "min": lo, "max": hi,
            "description": sv.get("description", ""),
            "derivative": typ_el.get("derivative"), "nominal": typ_el.get("nominal"),
        })
    read_model_exchange(root, model, cs, xml_path)
    return model


def enumeration_items(root, xml_path):
    """{type name: [item values]} of the <TypeDefinitions><SimpleType><Enumeration>s. The
    items of one type must be consecutive integers (the layer's range check, min..max, is
    then exactly "one of the items"), each value and name once."""
    out = {}
    for st in root.iterfind("TypeDefinitions/SimpleType"):
        en = st.find("Enumeration")
        if en is None:
            continue
        vals = [int(i.get("value")) for i in en.findall("Item")]
        names = [i.get("name") for i in en.findall("Item")]
        if not vals or sorted(vals) != list(range(min(vals), min(vals) + len(vals))) \
                or len(set(names)) != len(names):
            raise ModelDescriptionError(
                f"{xml_path}: Enumeration type '{st.get('name')}': items {list(zip(names, vals))} are not "
                "unique names with consecutive values")
        out[st.get("name")] = vals
    return out


def read_model_exchange(root, model, cs, xml_path):
    """<ModelExchange>: the continuous states, in the order of
    <ModelStructure><Derivatives> (FMI 2.0, 2.2.8), and the event indicators."""
    me = root.find("ModelExchange")
    model["me"] = None
    if me is None:
        return
    if me.get("modelIdentifier") != cs.get("modelIdentifier"):
        raise ModelDescriptionError(
            f"{xml_path}: <ModelExchange> and <CoSimulation> must share one modelIdentifier")
    ders = root.find("ModelStructure/Derivatives")
    unknowns = [] if ders is None else ders.findall("Unknown")
    states = []
    for u in unknowns:
        dv = model["vars"][int(u.get("index")) - 1]
        if dv["type"] != "Real" or dv["derivative"] is None:
            raise ModelDescriptionError(
                f"{xml_path}: <Derivatives> lists '{dv['name']}', which declares no derivative=")
        sv = model["vars"][int(dv["derivative"]) - 1]
        if sv["type"] != "Real" or sv["variability"] != "continuous":
            raise ModelDescriptionError(
                f"{xml_path}: '{dv['name']}' is the derivative of '{sv['name']}', "
                "which is not a continuous Real")
        states.append((sv, dv))
    declared = sum(1 for v in model["vars"] if v["derivative"] is not None)
    if declared != len(states):
        raise ModelDescriptionError(
            f"{xml_path}: {declared} variables declare derivative=, "
            f"<Derivatives> lists {len(states)}")
    model["me"] = {"states": states,
                   "nz": int(root.get("numberOfEventIndicators", "0"))}


def fmi3_value_references(model):
    """The FMI 3.0 value references of the model's variables (FMI 3.0 has one value
    reference space for all types, FMI 2.0 one per type): each variable keeps its FMI 2.0
    value reference unless a variable before it (in the order of <ModelVariables>) has it;
    then, and for the variables FMI 3.0 adds (the independent variable time, then the
    event indicators of a Model Exchange model), the next numbers above the largest FMI 2.0
    value reference. Returns {"vars": [vr per variable], "time": vr, "z": [vr per event
    indicator]}."""
    used, vrs = set(), []
    nxt = max((v["vr"] for v in model["vars"]), default=-1) + 1
    for v in model["vars"]:
        if v["vr"] in used:
            vrs.append(nxt)
            nxt += 1
        else:
            vrs.append(v["vr"])
            used.add(v["vr"])
    nz = model["me"]["nz"] if model["me"] else 0
    return {"vars": vrs, "time": nxt, "z": list(range(nxt + 1, nxt + 1 + nz))}


def for_fmi3(model):
    """The model with its FMI 3.0 value references and Enumerations as T_ENUMERATION."""
    refs = fmi3_value_references(model)
    out = dict(model)
    out["vars"] = [dict(v, vr=vr) for v, vr in zip(model["vars"], refs["vars"])]
    out["fmi3"] = refs
    return out


def type_enum(model, v):
    if v["type"] == "Enumeration" and "fmi3" in model:
        return "T_ENUMERATION"
    return TYPE_ENUM[v["type"]]


def fields(model):
    """One C field per base name; arrays sized by the largest index."""
    out = {}
    for v in model["vars"]:
        f = out.setdefault(v["base"], {"type": v["type"], "size": None, "desc": v["description"]})
        if f["type"] != v["type"]:
            raise ModelDescriptionError(f"'{v['name']}': array elements differ in type")
        if v["index"] is not None:
            f["size"] = max(f["size"] or 0, v["index"] + 1)
        elif f["size"] is not None:
            raise ModelDescriptionError(f"'{v['name']}' is both scalar and array")
    return out


def field_expr(v):
    return v["base"] if v["index"] is None else f"{v['base']}[{v['index']}]"


def write_header(model, path):
    lines = [
        "/* Generated by src/fmi/gen_vars.py from the model description. Do not edit. */",
        "#ifndef MODEL_VARS_H", "#define MODEL_VARS_H", "",
        "/* the FMI version this table is for: fmu.h takes it as FMI_VERSION where the build",
        "   defines none (a source FMU compiled by an importer that passes no -D) */",
        f"#define MODEL_FMI_VERSION {3 if 'fmi3' in model else 2}",
        f'#define MODEL_IDENTIFIER "{model["identifier"]}"',
        f'#define MODEL_GUID "{model["guid"]}"',
        f"#define MODEL_NVARS {len(model['vars'])}",
        "#define ARTIBUS_STRLEN 1024", "",
        "/* every variable of the model description, by name */",
        "typedef struct {",
    ]
    for base, f in fields(model).items():
        ctype = C_TYPE[f["type"]]
        dims = f"[{f['size']}]" if f["size"] else ""
        if f["type"] == "String":
            dims += "[ARTIBUS_STRLEN]"
        lines.append(f"    {ctype} {base}{dims};")
    lines += ["} ModelData;", "", "/* value references */"]
    for v in model["vars"]:
        suffix = "" if v["index"] is None else f"_{v['index']}"
        lines.append(f"#define VR_{v['base']}{suffix} {v['vr']}u  /* {v['name']} */")
    if "fmi3" in model:
        refs = model["fmi3"]
        lines += ["", "/* FMI 3.0: the independent variable time and the first event indicator */",
                  f"#define MODEL_VR_TIME {refs['time']}u"]
        if refs["z"]:
            lines.append(f"#define MODEL_VR_Z0 {refs['z'][0]}u")
    me = model["me"]
    if me:
        lines += ["", "/* Model Exchange: the continuous states x[i] in the order of "
                  "<Derivatives>, and the event indicators */",
                  f"#define MODEL_NX {len(me['states'])}",
                  f"#define MODEL_NZ {me['nz']}"]
        for i, (sv, dv) in enumerate(me["states"]):
            lines.append(f"/*   x[{i}] = {sv['name']}, dx[{i}] = {dv['name']} */")
    lines += ["", "#endif", ""]
    with open(path, "w") as fh:
        fh.write("\n".join(lines))


def write_source(model, path):
    lines = [
        "/* Generated by src/fmi/gen_vars.py from the model description. Do not edit. */",
        "#include <math.h>", "#include <stddef.h>", "#include <string.h>",
        '#include "vartable.h"', "",
        "const VarInfo VARS[MODEL_NVARS] = {",
    ]
    for v in model["vars"]:
        lo = c_double(v["min"]) if v["min"] is not None else "-INFINITY"
        hi = c_double(v["max"]) if v["max"] is not None else "INFINITY"
        lines.append(
            f'    {{ {c_string(v["name"])}, {v["vr"]}u, {type_enum(model, v)}, '
            f'C_{v["causality"].upper()}, V_{v["variability"].upper()}, '
            f'offsetof(ModelData, {field_expr(v)}), {lo}, {hi} }},')
    lines.append("};")
    lines.append("")
    # the Real outputs in the order of VARS, for the layer's finite-output check
    # after every step (check_outputs in fmi2Functions.c); NULL ends the list
    outputs = [f"&VARS[{i}]" for i, v in enumerate(model["vars"])
               if v["type"] == "Real" and v["causality"] == "output"]
    lines.append("const VarInfo *const REAL_OUTPUTS[] = { " + ", ".join(outputs + ["NULL"]) + " };")
    lines.append("")
    # per-type dense look-up: value reference -> index into VARS, -1 if none
    for tname in TYPES:
        idx = {v["vr"]: i for i, v in enumerate(model["vars"]) if type_enum(model, v) == tname}
        n = max(idx) + 1 if idx else 1
        table = ", ".join(str(idx.get(r, -1)) for r in range(n))
        lines.append(f"static const int LOOKUP_{tname}[{n}] = {{ {table} }};")
    lines += [
        "",
        "const VarInfo *vars_find(VarType type, unsigned vr) {",
        "    const int *lookup; size_t n;",
        "    switch (type) {",
    ]
    for tname in TYPES:
        lines.append(f"    case {tname}: lookup = LOOKUP_{tname}; "
                     f"n = sizeof(LOOKUP_{tname}) / sizeof(int); break;")
    lines += [
        "    default: return NULL;",
        "    }",
        "    if (vr >= n || lookup[vr] < 0) return NULL;",
        "    return &VARS[lookup[vr]];",
        "}",
        "",
        "void vars_set_start_values(ModelData *d) {",
        "    memset(d, 0, sizeof(*d));",
    ]
    for v in model["vars"]:
        if v["start"] is None:
            continue
        f = "d->" + field_expr(v)
        if v["type"] == "Real":
            lines.append(f"    {f} = {c_double(v['start'])};")
        elif v["type"] in ("Integer", "Enumeration"):
            lines.append(f"    {f} = {int(v['start'])};")
        elif v["type"] == "Boolean":
            lines.append(f"    {f} = {1 if v['start'] in ('true', '1') else 0};")
        else:
            if len(v["start"].encode()) >= 1024:
                raise ModelDescriptionError(f"start value of '{v['name']}' is too long")
            lines.append(f"    strcpy({f}, {c_string(v['start'])});")
    lines += ["}", ""]
    me = model["me"]
    if me:
        names = ", ".join(c_string(sv["name"]) for sv, _ in me["states"])
        noms = ", ".join(c_double(sv["nominal"] or "1") for sv, _ in me["states"])
        lines += [f"const char *const X_NAME[MODEL_NX] = {{ {names} }};",
                  f"const double X_NOMINAL[MODEL_NX] = {{ {noms} }};", ""]
    with open(path, "w") as fh:
        fh.write("\n".join(lines))


def main(argv):
    fmi3 = argv[3:] == ["--fmi", "3"]
    if len(argv) != 3 and not fmi3:
        sys.stderr.write(__doc__)
        return 2
    try:
        model = read(argv[1])
        if fmi3:
            model = for_fmi3(model)
    except (ModelDescriptionError, ET.ParseError) as e:
        sys.stderr.write(f"gen_vars: {e}\n")
        return 1
    os.makedirs(argv[2], exist_ok=True)
    write_header(model, os.path.join(argv[2], "model_vars.h"))
    write_source(model, os.path.join(argv[2], "model_vars.c"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

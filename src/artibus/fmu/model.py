"""An FMU's interface as artibus reads it, one model for FMI 2.0 and FMI 3.0 (``Model``,
``Variable``, ``model_of``): FMPy's model description with each variable carrying

- ``type``: its own FMI type, as its modelDescription.xml names it (FMI 2.0: Real, Integer,
  Enumeration, Boolean, String; FMI 3.0: Float64, Float32, Int8 ... UInt64, Boolean, String,
  Enumeration, Binary, Clock): the get/set calls use it (artibus.fmu.fmi2, artibus.fmu.fmi3);
- ``kind``: the family of SSP's type choice it connects as (SSP 2.0 docs/4___common_content.adoc,
  "Type Choice", and "Transformation Choice": a LinearTransformation applies to Real, Float64 or
  Float32, an IntegerMappingTransformation to the integer types): Real, Integer, Enumeration,
  Boolean, String, Binary or Clock; SSP 1.0's connector types are these names. A bench's
  typing rule, the parameter checks and the runner's connections speak in kinds;
- ``shape``: its array dimensions (FMI 3.0 2.4.7.6, <Dimension>: a fixed ``start`` or a
  structural parameter's start; FMPy resolves both), () for a scalar; ``size`` the number of
  values a get or set of it moves (nValues, FMI 3.0 2.2.6.2);
- ``unit``: its own unit or its declared type's.

Everything else (causality, start, min, max, declaredType, the model's unit definitions,
default experiment, interfaces) is FMPy's, read through. One Model per description, made once.
"""
import math

#: FMI 3.0's and FMI 2.0's types by the SSP kind they connect as
KINDS = {"Real": "Real", "Float64": "Real", "Float32": "Real",
         "Integer": "Integer", "Int8": "Integer", "UInt8": "Integer", "Int16": "Integer",
         "UInt16": "Integer", "Int32": "Integer", "UInt32": "Integer", "Int64": "Integer",
         "UInt64": "Integer", "Enumeration": "Enumeration", "Boolean": "Boolean",
         "String": "String", "Binary": "Binary", "Clock": "Clock"}
#: kinds that are no numbers: a result table does not hold them, a bench connects them only
#: through FMI-LS-BUS terminals
NOT_NUMBERS = ("Binary", "Clock")


class Variable:
    """One variable of an FMU (see the module's docstring); the attributes not named here
    are those of FMPy's ModelVariable (``declared``)."""
    __slots__ = ("declared", "name", "valueReference", "type", "kind", "shape", "size",
                 "causality", "variability", "unit", "start")

    def __init__(self, declared, structural=None):
        self.declared = declared
        self.name, self.valueReference = declared.name, declared.valueReference
        self.type = declared.type
        self.kind = KINDS.get(declared.type, declared.type)
        self.shape = tuple(declared.shape or ()) if declared.dimensions else ()
        if structural and declared.dimensions:      # sized by structural parameters set in Configuration Mode
            self.shape = tuple(int(structural.get(d.valueReference, n)) if d.start is None else int(d.start)
                               for d, n in zip(declared.dimensions, self.shape))
        self.size = math.prod(self.shape) if self.shape else 1
        self.causality, self.variability = declared.causality, declared.variability
        dt = declared.declaredType
        self.unit = declared.unit or (dt.unit if dt is not None else None)
        self.start = declared.start

    def __getattr__(self, name):          # min, max, nominal, declaredType, description, ...
        if name == "declared":            # (not yet set, as while unpickling: no recursion)
            raise AttributeError(name)
        return getattr(self.declared, name)

    def __repr__(self):
        shape = f"[{','.join(map(str, self.shape))}]" if self.shape else ""
        return f"Variable({self.name}{shape}: {self.type}, {self.causality})"


class _Output:
    """ModelStructure's Output (or InitialUnknown) with the model's Variables."""
    __slots__ = ("variable", "dependencies", "declared")

    def __init__(self, declared, by_id):
        self.declared = declared
        self.variable = by_id.get(id(declared.variable), declared.variable)
        deps = declared.dependencies
        self.dependencies = None if deps is None else [by_id.get(id(d), d) for d in deps]

    def __getattr__(self, name):          # index, dependenciesKind, sourceline
        if name == "declared":
            raise AttributeError(name)
        return getattr(self.declared, name)


class Model:
    """An FMU's model description with artibus's Variables (see the module's docstring)."""

    def __init__(self, md, structural=None):
        """``structural``: {value reference: value} of structural parameters set in Configuration
        Mode (FMI 3.0 2.3, "Configuration Mode": it resizes the arrays they dimension)."""
        from artibus.bench.fmi import fmi_major
        self.description = md
        self.fmi = fmi_major(md.fmiVersion)
        self.modelVariables = [Variable(v, structural) for v in md.modelVariables]
        by_id = {id(d): v for d, v in zip(md.modelVariables, self.modelVariables)}
        self.outputs = [_Output(o, by_id) for o in md.outputs]
        self.by_name = {v.name: v for v in self.modelVariables}

    def __getattr__(self, name):          # modelName, unitDefinitions, defaultExperiment, ...
        if name == "description":         # (not yet set: no recursion)
            raise AttributeError(name)
        return getattr(self.description, name)

    @property
    def time(self):
        """The independent variable (FMI 3.0 requires one; FMI 2.0's is optional), or None."""
        return next((v for v in self.modelVariables if v.causality == "independent"), None)


_MODELS = {}                     # id(description) -> (description, its Model)
_MODELS_KEPT = 256


def model_of(md):
    """The Model of FMPy's description ``md`` (made once per description; a Model as it is)."""
    if isinstance(md, Model):
        return md
    kept = _MODELS.get(id(md))
    if kept is not None and kept[0] is md:
        return kept[1]
    model = Model(md)
    if len(_MODELS) >= _MODELS_KEPT:
        _MODELS.pop(next(iter(_MODELS)))
    _MODELS[id(md)] = (md, model)     # (FMPy's descriptions have __slots__: no attribute on them)
    return model


def read_description(path, validate=True):
    """fmpy.read_model_description of the FMU or modelDescription.xml ``path``, with what FMPy
    0.3 leaves out put back: the min and max of FMI 3.0's unsigned integer types (UInt8 ..
    UInt64; FMPy reads them for Float*, Int* and Enumeration only), so that a value outside
    them is refused (FMI 3.0 2.4.7.4.2)."""
    from fmpy import read_model_description
    md = read_model_description(str(path), validate=validate)
    unsigned = {v.name: v for v in md.modelVariables if v.type.startswith("UInt")}
    if unsigned:
        import zipfile

        from lxml import etree
        if zipfile.is_zipfile(str(path)):
            with zipfile.ZipFile(str(path)) as z:
                root = etree.fromstring(z.read("modelDescription.xml"))
        else:
            root = etree.parse(str(path)).getroot()
        for el in root.iterfind("ModelVariables/*"):
            v = unsigned.get(el.get("name"))
            if v is not None:
                v.min, v.max = el.get("min"), el.get("max")
    return md

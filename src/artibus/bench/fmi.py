"""Which FMI version an FMU is (``fmi_major``: 2.0, or any 3.x the FMI 3.0 schema allows), the
ranges of FMI 3.0's integer types, and which build of its FMUs a bench runs with
(``FMI_VERSIONS``, ``fmi_choice``). An FMU's variables, FMI 2.0 and 3.0 alike, are read
through artibus.fmu.model."""
import re

from artibus.base import ArtibusError

#: the range of each FMI 3.0 integer type (FMI 3.0 2.4.7.4.2): a value outside it is refused,
#: never wrapped by the C call
INTEGER_RANGE = {"Int8": (-2**7, 2**7 - 1), "UInt8": (0, 2**8 - 1), "Int16": (-2**15, 2**15 - 1),
                 "UInt16": (0, 2**16 - 1), "Int32": (-2**31, 2**31 - 1), "UInt32": (0, 2**32 - 1),
                 "Int64": (-2**63, 2**63 - 1), "UInt64": (0, 2**64 - 1)}
#: the builds of a bench's FMUs artibus runs: "2" (fmus/<Name>.fmu), "3" (fmus/fmi3/<Name>.fmu)
FMI_VERSIONS = ("2", "3")


#: the fmiVersion values the FMI 3.0 schema allows (fmi3ModelDescription.xsd, the attribute
#: fmiVersion: 3.0, 3.0.1, 3.0.2, 3.1, 3.0-rc.2, ...): Dymola writes "3.0.1", the standard's 3.0.2
_FMI3_VERSION = re.compile(r"3[.](0|[1-9][0-9]*)([.](0|[1-9][0-9]*))?(-.+)?")


def fmi_major(version):
    """2 for fmiVersion "2.0", 3 for every fmiVersion the FMI 3.0 schema allows, else None
    (FMI 1.0, a later major version: artibus refuses them by name)."""
    if version == "2.0":
        return 2
    return 3 if version and _FMI3_VERSION.fullmatch(version) else None


def fmi_choice(fmi):
    """``--fmi``'s value: None (the bench's choice: the builds its .ssd names,
    resources/<Name>.fmu FMI 2.0, resources/fmi3/<Name>.fmu FMI 3.0), "2" or
    "3" (every FMU of the bench in that build); ArtibusError otherwise."""
    if fmi is None:
        return None
    if str(fmi) not in FMI_VERSIONS:
        raise ArtibusError(f"--fmi {fmi}: expected {' or '.join(FMI_VERSIONS)}")
    return str(fmi)


def build_of(ref, fmi, where):
    """The file of the FMU a bench names ``ref`` (resources/<Name>.fmu or
    resources/fmi3/<Name>.fmu) in the build ``fmi``: fmus/<Name>.fmu (FMI
    2.0) or fmus/fmi3/<Name>.fmu (FMI 3.0, CMake's ARTIBUS_FMI3); an error
    naming the component's line (``where``) and the missing build."""
    from pathlib import PurePosixPath

    from artibus.base import fmu_dir
    name = PurePosixPath(ref).name
    f = (fmu_dir() if fmi == "2" else fmu_dir() / "fmi3") / name
    if not f.is_file():
        how = "the set-up command of the README" if fmi == "2" else "CMake with -DARTIBUS_FMI3=ON"
        raise ArtibusError(f"{where}: source=\"{ref}\": {PurePosixPath(name).stem} has no FMI {fmi}.0 build "
                           f"({f} is not built; {how} builds it)")
    return f


def pack_file(bench, fmi, refs):
    """Where the bench's pack with the build ``fmi`` of its FMUs goes (refs: the
    files it packs): fmus/<Bench>.ssp as its .ssd says (fmi None, or "2" when it
    names no FMI 3.0 FMU), fmus/fmi3/<Bench>.ssp with every FMU's FMI 3.0 build,
    fmus/fmi2/<Bench>.ssp with every FMU's FMI 2.0 build of a bench that names
    FMI 3.0 ones."""
    from artibus.base import fmu_dir
    if fmi == "3":
        return fmu_dir() / "fmi3" / f"{bench}.ssp"
    if fmi == "2" and any(r.startswith("resources/fmi3/") and r.endswith(".fmu") for r in refs):
        return fmu_dir() / "fmi2" / f"{bench}.ssp"
    return fmu_dir() / f"{bench}.ssp"


def add_fmi_option(parser, verb):
    """The command line's --fmi of ``verb`` (run, sweep, pack, replay, bode: a bench's FMUs; simulate: one FMU)."""
    if verb == "simulate":
        parser.add_argument("--fmi", choices=FMI_VERSIONS, default="2",
                            help="run the FMI 3.0 build of a built FMU (fmus/fmi3/<Name>.fmu; default 2)")
        return
    parser.add_argument("--fmi", choices=FMI_VERSIONS, default=None,
                        help="every FMU of the bench in its FMI 2.0 (fmus/<Name>.fmu) or FMI 3.0 build "
                             "(fmus/fmi3/<Name>.fmu), packed as fmus/fmi3/<BENCH>.ssp (default: the builds "
                             "the bench's .ssd names, resources/<Name>.fmu or resources/fmi3/<Name>.fmu)")


def simulated_fmu(fmu, arg, fmi):
    """The file `artibus simulate ARG --fmi FMI` runs: ``fmu`` (ARG's FMI 2.0
    file) with "2", its FMI 3.0 build fmus/fmi3/<Name>.fmu with "3" (a name
    of a built FMU only: an .fmu's path runs as it is, without --fmi)."""
    from pathlib import Path

    from artibus.base import fmu_dir
    if fmi != "3":
        return fmu
    if Path(arg).suffix == ".fmu":       # the parameters are checked against its FMI 2.0 declarations
        raise ArtibusError(f"--fmi 3 takes the name of a built FMU, not a path ({arg}): "
                           "give an FMI 3.0 .fmu's path without --fmi")
    run = fmu_dir() / "fmi3" / f"{arg}.fmu"
    if not run.is_file():
        raise ArtibusError(f"{run}: no FMI 3.0 build of {arg} (built with -DARTIBUS_FMI3=ON)")
    return run

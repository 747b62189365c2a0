"""What artibus has, for the command line's `artibus list` and `artibus info`: the
benches (their components, connections, variants, bound values) and the FMUs
(their variables, units, defaults)."""
from pathlib import Path

from artibus.base import ArtibusError, fmu_dir, fmu_path


def _fmu_names():
    return sorted(p.stem for p in fmu_dir().glob("*.fmu"))


def cmd_info(args):
    from fmpy import read_model_description
    from artibus.bench import ssp
    name = str(args.fmu)
    if name.endswith(".ssp") or name in ssp.bench_names():
        return _info_ssp(name)
    p = Path(name)
    if p.suffix == ".fmu":
        if not p.is_file():
            raise ArtibusError(f"{p}: no such file")
        path = p
    elif (fmu_dir() / f"{name}.fmu").is_file():
        path = fmu_dir() / f"{name}.fmu"
    else:
        import difflib
        known = ssp.bench_names() + _fmu_names()
        close = difflib.get_close_matches(name, known, n=3, cutoff=0.6)
        hint = f"; did you mean {' or '.join(close)}?" if close else f" (see `artibus list`)"
        raise ArtibusError(f"{name}: no such bench or FMU{hint}")
    try:
        md = read_model_description(str(path))
    except Exception as e:  # a corrupt or foreign file: name it
        raise ArtibusError(f"{path}: not a readable FMU ({e})") from None
    print(f"{md.modelName}: {md.description}")
    de = md.defaultExperiment
    if de:
        print(f"default experiment: {de.startTime} .. {de.stopTime} s, step {de.stepSize} s")
    for caus in ("parameter", "input", "output"):
        vs = [v for v in md.modelVariables if v.causality == caus]
        print(f"\n{caus}s ({len(vs)}):")
        for v in vs:
            start = f" = {v.start}" if v.start is not None else ""
            print(f"  {v.name:18s} {v.type:8s}{start:>12s}  {v.description or ''}")
    return 0


def _info_ssp(path):
    from artibus.bench import ssp
    bench = ssp.read(ssp.ssp_path(path))
    print(f"{bench.name}: {bench.file}")
    print(f"default experiment: {bench.start_time} .. {bench.stop_time} s")
    print("\ncomponents:")
    for c in bench.components.values():
        step = f", step {c.step} s" if c.step else ""
        print(f"  {c.path}: {c.source}{step}, {len(c.parameters)} parameters bound")
    print("\nconnections:")
    for c in bench.connections:
        tr = f"  (x {c.factor:g} + {c.offset:g})" if (c.factor, c.offset) != (1.0, 0.0) else ""
        print(f"  {c.start[0]}.{c.start[1]} -> {c.end[0]}.{c.end[1]}{tr}")
    if bench.version == "2.0":           # its FMI-LS-BUS network (artibus.bench.ssp2)
        from artibus.bench.ssp2 import network_lines
        print("", *network_lines(ssp.ssp_path(path)), sep="\n")
    return 0


def cmd_list(args):
    """One line per bench and per FMU; --parameters: every bench's bound parameters too."""
    from artibus.bench import ssp
    names = ssp.bench_names()
    print(f"benches ({len(names)}; `artibus info BENCH` for one, `artibus run BENCH` to run it):"
          if names else "no benches in ssp/benches/")
    for name in names:
        try:
            bench = ssp.read(ssp.ssp_path(name))
        except Exception as e:  # an unpacked or broken bench is still listed
            print(f"  {name}: ({e})")
            continue
        variants = ssp.variants(ssp.ssp_path(name))
        more = f"; variants: {', '.join(variants)}" if variants else ""
        print(f"  {name}: {', '.join(bench.components)}; {bench.stop_time:g} s{more}")
        if args.parameters:
            for c in bench.components.values():
                for k, v in sorted(c.parameters.items()):
                    print(f"      {c.path}.{k} = {v}")
    fmus = _fmu_names()
    if fmus:
        from fmpy import read_model_description
        print(f"\nFMUs ({len(fmus)} in {fmu_dir()}; `artibus info FMU` for its variables):")
        for f in fmus:
            try:
                d = read_model_description(str(fmu_dir() / f"{f}.fmu")).description or ""
            except Exception as e:
                d = f"(unreadable: {e})"
            print(f"  {f}: {d[:100] + ('...' if len(d) > 100 else '')}")
    if not args.parameters:
        print("\n(`artibus list --parameters` adds every bench's parameter values)")
    return 0


def fmu_arg(text):
    """an FMU named on the command line: a path to an .fmu, or the name of a built FMU (never a bench)"""
    p = Path(text)
    wrong_kind("simulate", text)
    return p if p.suffix == ".fmu" else fmu_path(text)


def wrong_kind(verb, text):
    """A bench (a name of ssp/benches, an .ssp) given to ``simulate`` or an FMU (an
    .fmu, the name of a built FMU that is no bench) given to ``run``: an error
    saying which verb takes it, before any look-up says "not built" or "no such bench"."""
    from artibus.base import fmu_dir
    from artibus.bench import ssp
    p = Path(text)
    benches = ssp.bench_names()
    if verb == "simulate" and (p.suffix.lower() == ".ssp" or (p.suffix == "" and text in benches)):
        raise ArtibusError(f"simulate {text}: a bench (an SSP system of FMUs), not an FMU: run it with "
                           f"`artibus run {text}`; simulate runs one FMU alone (`artibus list` shows both)")
    if verb == "run" and (p.suffix.lower() == ".fmu" or (text not in benches and p.suffix == ""
                                                       and (fmu_dir() / f"{text}.fmu").is_file())):
        raise ArtibusError(f"run {text}: an FMU, not a bench: simulate it alone with "
                           f"`artibus simulate {text}`; run runs a bench (`artibus list` shows both)")

#!/usr/bin/env bash
# The Modelica Reference-FMUs (BSD-2-Clause), FMI 2.0, built from their sources
# for the tests (tests/test_reference_fmus.py): BouncingBall, Dahlquist,
# Feedthrough, Resource, Stair, VanDerPol as FMI 2.0 FMUs (each both Model
# Exchange and Co-Simulation; the tests use Co-Simulation), linux64, and the same
# six as FMI 3.0 (FMI_VERSION=3, x86_64-linux) in fmi3/: Feedthrough has every FMI 3.0
# variable type, Stair ends the run through fmi3DoStep's terminateSimulation; and the FMI
# 3.0-only LinearTransform (arrays) and Clocks (clocks, Event Mode) in fmi3/.
#
# Their sources come from crates.io: the crate fmi-sys carries the FMI 3.0
# standard's sources, whose docs/Reference-FMUs is the Reference-FMUs' own
# tree (its CMakeLists.txt, models, LICENSE.txt). The crate is downloaded with
# cargo (its ordinary client; nothing is compiled in Rust), the FMUs are built
# with the Reference-FMUs' own CMake build (FMI_VERSION=2) into the cache
# outside the clone, once per machine, and linked as .tools/reference-fmus/.
# Without cargo the tests that use them say so and are skipped.
#
# usage: scripts/build_reference_fmus.sh
set -euo pipefail
. "$(dirname "$0")/build_common.sh"     # CACHE, quiet, crate_source

FMI_SYS_VERSION=0.5.0
MODELS="BouncingBall Dahlquist Feedthrough Resource Stair VanDerPol"
# FMI 3.0 only: LinearTransform (array variables whose dimensions are structural
# parameters, FMI 3.0 2.4.7.6) and Clocks (input, output and countdown clocks, Event Mode)
MODELS3="LinearTransform Clocks"
out="$CACHE/reference-fmus-fmi-sys-$FMI_SYS_VERSION-fmi23c"
link="$ROOT/.tools/reference-fmus"

have_all() {
  local m
  for m in $MODELS; do [ -f "$out/$m.fmu" ] && [ -f "$out/fmi3/$m.fmu" ] || return 1; done
  for m in $MODELS3; do [ -f "$out/fmi3/$m.fmu" ] || return 1; done
  [ -f "$out/ref/Dahlquist_ref.csv" ] || return 1
}

if ! have_all; then
  if ! command -v cargo >/dev/null 2>&1; then
    echo "reference-fmus: no cargo: the Reference-FMUs are not built; their tests will be skipped"
    exit 0
  fi
  (
    flock 9
    have_all && exit 0
    echo "reference-fmus: building the Reference-FMUs (FMI 2.0 and 3.0) from the crate fmi-sys $FMI_SYS_VERSION into $out"
    rm -rf "$out.build" "$out.build3" "$out.src"
    src_dir="$(QUIET_LOG="$out.log" QUIET_TAG=reference-fmus crate_source fmi-sys "$FMI_SYS_VERSION" "$out.crate")"
    src_dir="$src_dir/fmi-standard3/docs/Reference-FMUs"
    if [ ! -f "$src_dir/CMakeLists.txt" ]; then
      echo "reference-fmus: no Reference-FMUs sources in the crate fmi-sys $FMI_SYS_VERSION ($src_dir)" >&2
      exit 1
    fi
    # a copy of the sources, with one fix: an Integer, Boolean or String variable
    # without a variability is "continuous" by FMI 2.0's default, which the
    # standard forbids (FMPy's validation refuses Stair's counter): such a
    # variable is made "discrete" in the model descriptions (FMI2.xml), as later
    # Reference-FMUs releases declare it
    cp -r "$src_dir" "$out.src"
    python3 - "$out.src" $MODELS $MODELS3 <<'PY'
import re, sys
from pathlib import Path
for m in sys.argv[2:]:
    f = Path(sys.argv[1]) / m / "FMI2.xml"
    if not f.is_file():           # (an FMI 3.0-only model)
        f3 = Path(sys.argv[1]) / m / "FMI3.xml"
        f3.write_text(f3.read_text(encoding="utf-8").replace('fmiVersion="3.0-rc.2"', 'fmiVersion="3.0"'), encoding="utf-8")
        continue
    text = f.read_text(encoding="utf-8")
    def fix(v):
        head, body = v.group(1), v.group(2)
        if "variability=" in head or not re.match(r"\s*<(Integer|Boolean|String)\b", body):
            return v.group(0)
        return head.replace("<ScalarVariable ", '<ScalarVariable variability="discrete" ', 1) + body
    f.write_text(re.sub(r"(<ScalarVariable [^>]*>)(\s*<\w+)", fix, text), encoding="utf-8")
    # FMI 3.0: these sources predate the release and say fmiVersion="3.0-rc.2"; their C API
    # (include/fmi3*.h) is the released 3.0's, line for line, and the descriptions pass
    # the 3.0 schema (tests/test_reference_fmus.py checks it): declared "3.0"
    f3 = Path(sys.argv[1]) / m / "FMI3.xml"
    f3.write_text(f3.read_text(encoding="utf-8").replace('fmiVersion="3.0-rc.2"', 'fmiVersion="3.0"'), encoding="utf-8")
PY
    QUIET_LOG="$out.log" QUIET_TAG=reference-fmus quiet \
      cmake -S "$out.src" -B "$out.build" -DFMI_VERSION=2 -DCMAKE_BUILD_TYPE=Release
    # shellcheck disable=SC2086
    QUIET_LOG="$out.log" QUIET_TAG=reference-fmus quiet \
      cmake --build "$out.build" -j2 --target $MODELS
    mkdir -p "$out/fmi3"
    for m in $MODELS; do cp "$out.build/dist/$m.fmu" "$out/$m.fmu"; done
    # the FMI 3.0 builds, from the same sources (their FMI3.xml need no fix: an Int32 or
    # Boolean without a variability is discrete by FMI 3.0's default)
    QUIET_LOG="$out.log" QUIET_TAG=reference-fmus quiet \
      cmake -S "$out.src" -B "$out.build3" -DFMI_VERSION=3 -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_C_FLAGS=-Wno-error=stringop-truncation    # Resource's strncpy warning is an error with -Werror in their FMI 3.0 build
    # shellcheck disable=SC2086
    QUIET_LOG="$out.log" QUIET_TAG=reference-fmus quiet \
      cmake --build "$out.build3" -j2 --target $MODELS $MODELS3
    for m in $MODELS $MODELS3; do cp "$out.build3/dist/$m.fmu" "$out/fmi3/$m.fmu"; done
    cp "$src_dir/LICENSE.txt" "$out/LICENSE.txt"
    # the reference results their sources carry, in the FMI cross-check's layout: <Model>_ref.csv
    # (the results), <Model>_ref.opt (start, stop, step, relative tolerance), <Model>_in.csv (inputs)
    mkdir -p "$out/ref"
    for m in $MODELS $MODELS3; do
      for f in "$src_dir/$m/${m}_ref.csv" "$src_dir/$m/${m}_ref.opt" "$src_dir/$m/${m}_in.csv"; do
        if [ -f "$f" ]; then cp "$f" "$out/ref/"; fi
      done
    done
    echo "fmi-sys $FMI_SYS_VERSION (crates.io): fmi-standard3/docs/Reference-FMUs, FMI_VERSION=2," \
      "Integer/Boolean/String variables without a variability declared discrete; fmi3/: FMI_VERSION=3, fmiVersion 3.0-rc.2 declared 3.0" >"$out/SOURCE.txt"
    rm -rf "$out.build" "$out.build3" "$out.src"
  ) 9>"$out.lock"
fi
if have_all && [ "$(readlink "$link" 2>/dev/null)" != "$out" ]; then
  mkdir -p "$ROOT/.tools"
  ln -sfn "$out" "$link"
fi

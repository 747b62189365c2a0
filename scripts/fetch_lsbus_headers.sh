#!/usr/bin/env bash
# The FMI-LS-BUS 1.0 C headers of the Modelica Association (BSD-2-Clause):
# fmi3LsBus.h, fmi3LsBusCan.h (the operations' packed structs and codes) and
# fmi3LsBusUtil.h, fmi3LsBusUtilCan.h (the macros that build and read them), with
# FMI 3.0's fmi3PlatformTypes.h they include, for the tests that check artibus's
# own codec (src/fmi/lsbus_can.c) and FMUs against them
# (tests/test_lsbus_official_headers.py).
#
# They come from crates.io: the crate fmi-sys 0.6.0 carries the standard's
# fmi-ls-bus/headers (and fmi-standard3/headers). The crate is downloaded with
# cargo (build_common.sh's crate_source; nothing is compiled in Rust), the
# headers copied into the cache outside the clone, once per machine, and linked
# as .tools/fmi-ls-bus/. Without cargo the tests that use them say so and are
# skipped.
#
# usage: scripts/fetch_lsbus_headers.sh
set -euo pipefail
. "$(dirname "$0")/build_common.sh"     # CACHE, quiet, crate_source

FMI_SYS_VERSION=0.6.0
HEADERS="fmi3LsBus.h fmi3LsBusCan.h fmi3LsBusUtil.h fmi3LsBusUtilCan.h"
out="$CACHE/fmi-ls-bus-headers-fmi-sys-$FMI_SYS_VERSION"
link="$ROOT/.tools/fmi-ls-bus"

have_all() {
  local h
  for h in $HEADERS fmi3PlatformTypes.h; do [ -f "$out/$h" ] || return 1; done
}

if ! have_all; then
  if ! command -v cargo >/dev/null 2>&1; then
    echo "fmi-ls-bus: no cargo: the FMI-LS-BUS headers are not fetched; their tests will be skipped"
    exit 0
  fi
  (
    flock 9
    have_all && exit 0
    echo "fmi-ls-bus: the FMI-LS-BUS headers from the crate fmi-sys $FMI_SYS_VERSION into $out"
    src="$(QUIET_LOG="$out.log" QUIET_TAG=fmi-ls-bus crate_source fmi-sys "$FMI_SYS_VERSION" "$out.crate")"
    for h in $HEADERS; do
      if [ ! -f "$src/fmi-ls-bus/headers/$h" ]; then
        echo "fmi-ls-bus: no $h in the crate fmi-sys $FMI_SYS_VERSION ($src/fmi-ls-bus/headers)" >&2
        exit 1
      fi
    done
    rm -rf "$out.tmp"
    mkdir -p "$out.tmp"
    for h in $HEADERS; do cp "$src/fmi-ls-bus/headers/$h" "$out.tmp/"; done
    cp "$src/fmi-standard3/headers/fmi3PlatformTypes.h" "$out.tmp/"
    echo "fmi-sys $FMI_SYS_VERSION (crates.io): fmi-ls-bus/headers/{${HEADERS// /,}}," \
      "fmi-standard3/headers/fmi3PlatformTypes.h, unchanged" >"$out.tmp/SOURCE.txt"
    rm -rf "$out"
    mv "$out.tmp" "$out"
  ) 9>"$out.lock"
fi
if have_all && [ "$(readlink "$link" 2>/dev/null)" != "$out" ]; then
  mkdir -p "$ROOT/.tools"
  ln -sfn "$out" "$link"
fi

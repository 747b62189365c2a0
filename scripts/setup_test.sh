#!/usr/bin/env bash
# What the tests need beyond the main job (./test.sh runs this first):
#   the apt packages of the test tools (Wine for the win64 DLLs, Chromium for the
#   reports' browser checks),
#   everything scripts/setup.sh builds, with every platform's binaries
#   (scripts/setup.sh --all-platforms: the win64 DLLs packed into each FMU, and
#   the Wine prefix the win64 tests run them in),
#   the test extras in .venv (pytest, pytest-xdist, mkdocs, nbclient, libcosimpy, ecospy,
#   fmu-manipulation-toolbox),
#   fmi-sim (crates.io), a second importer every FMU is run in,
#   the Modelica Reference-FMUs (built from the crate fmi-sys), FMUs made by others,
#   the FMI-LS-BUS C headers (from the same crate), the standard's own operation macros.
# The third-party builds (SUNDIALS linux/win64, fmi-sim, the Wine prefix) are cached
# outside the clone ($ARTIBUS_CACHE, scripts/build_common.sh). Safe to run again.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/build_common.sh        # CACHE, step, apt_install, SUDO

TEST_APT_PACKAGES="wine64 chromium libtbb12 qemu-user"     # libtbb12: ecos (ecospy), another SSP master in the tests; qemu-user: the aarch64 binaries
apt_install $TEST_APT_PACKAGES

# the Wine prefix is made by build_win64.sh now that Wine is installed
bash scripts/setup.sh --all-platforms

stamp=".venv/.artibus-installed-test"
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
  step "installing the test extras into .venv (pytest, mkdocs, nbclient, libcosimpy, ecospy, fmu-manipulation-toolbox; about 30 s)" \
    .venv/bin/python -m pip install -q -e '.[test]'
  touch "$stamp"
fi

# fmi-sim (crates.io), a second importer the tests run every FMU in. It needs a
# recent Rust toolchain (rustup's, not Debian 12's) and libclang; without them
# the tests that use it say so and are skipped. Built once per machine into the
# cache outside the clone, linked as .tools/bin/fmi-sim.
FMI_SIM_VERSION=0.7.0
fmi_sim="$CACHE/fmi-sim-$FMI_SIM_VERSION"
if [ ! -x "$fmi_sim/bin/fmi-sim" ] && command -v cargo >/dev/null 2>&1; then
  if ! dpkg -s libclang-dev >/dev/null 2>&1; then
    $SUDO apt-get install -y -qq --no-install-recommends libclang-dev >/dev/null || true
  fi
  echo "setup: building fmi-sim $FMI_SIM_VERSION from crates.io into $fmi_sim (a few minutes, once per machine)"
  (
    flock 9
    [ -x "$fmi_sim/bin/fmi-sim" ] || cargo install -q fmi-sim --version "$FMI_SIM_VERSION" --locked --root "$fmi_sim" \
      || echo "setup: fmi-sim could not be built; its tests will be skipped"
  ) 9>"$fmi_sim.lock"
fi
if [ -x "$fmi_sim/bin/fmi-sim" ] && [ "$(readlink .tools/bin/fmi-sim 2>/dev/null)" != "$fmi_sim/bin/fmi-sim" ]; then
  mkdir -p .tools/bin
  ln -sfn "$fmi_sim/bin/fmi-sim" .tools/bin/fmi-sim
fi

# fmirs (tools/fmirs): a small command line on fmi-rs (crates.io), the engine of the
# Modelica Association's importer fmusim, which itself is on no package registry
# (docs/developer/fmi3.md, "fmusim"); tests/test_fmirs.py validates and simulates
# every FMU with it. Built once per version of its sources into the cache, linked
# as .tools/bin/fmirs; without cargo its tests say so and are skipped.
fmirs_key="$(cat tools/fmirs/Cargo.toml tools/fmirs/Cargo.lock tools/fmirs/src/main.rs | sha256sum | cut -c1-12)"
fmirs="$CACHE/fmirs-$fmirs_key"
if [ ! -x "$fmirs/bin/fmirs" ] && command -v cargo >/dev/null 2>&1; then
  echo "setup: building fmirs (fmi-rs 0.3.4 from crates.io) into $fmirs (about 3 minutes, once per machine)"
  (
    flock 9
    [ -x "$fmirs/bin/fmirs" ] || CARGO_TARGET_DIR="$fmirs.build" cargo install -q --path tools/fmirs --locked \
      --root "$fmirs" || echo "setup: fmirs could not be built; its tests will be skipped"
    rm -rf "$fmirs.build"     # (the build's 300 MB, outside the clone)
  ) 9>"$fmirs.lock"
fi
if [ -x "$fmirs/bin/fmirs" ] && [ "$(readlink .tools/bin/fmirs 2>/dev/null)" != "$fmirs/bin/fmirs" ]; then
  mkdir -p .tools/bin
  ln -sfn "$fmirs/bin/fmirs" .tools/bin/fmirs
fi

# the Modelica Reference-FMUs (FMI 2.0), a test set of FMUs made by others
# (tests/test_reference_fmus.py): built from their sources in the crate fmi-sys
# (crates.io) once per machine into the cache, linked as .tools/reference-fmus/
bash scripts/build_reference_fmus.sh || echo "setup: the Reference-FMUs could not be built; their tests will be skipped"

# the FMI-LS-BUS 1.0 C headers (the Modelica Association's, from the crate fmi-sys on
# crates.io), the standard's own operation macros our codec and FMUs are checked against
# (tests/test_lsbus_official_headers.py): once per machine into the cache, linked as .tools/fmi-ls-bus/
bash scripts/fetch_lsbus_headers.sh || echo "setup: the FMI-LS-BUS headers could not be fetched; their tests will be skipped"

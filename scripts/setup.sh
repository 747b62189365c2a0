#!/usr/bin/env bash
# Everything artibus needs on a Debian machine, then the build:
#   apt packages (compiler, CMake, SUNDIALS, Eigen, Python venv),
#   a Python venv in .venv with the artibus package (pyproject.toml),
#   every FMU built into fmus/.
# Safe to run again: it installs only what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES="cmake make g++ libsundials-dev libeigen3-dev python3 python3-venv python3-pip mingw-w64 wine64 dpkg-dev chromium libtbb12"
missing=""
for p in $APT_PACKAGES; do
  dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"
done
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
if [ -n "$missing" ]; then
  echo "setup: installing$missing"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi

# Debian's source packages, for SUNDIALS built for win64 (scripts/build_win64.sh):
# a deb-src entry for this release's main, once
if ! grep -rqsE '^(deb-src|Types:.*deb-src)' /etc/apt/sources.list /etc/apt/sources.list.d/; then
  echo "setup: adding a deb-src entry (Debian's source packages)"
  printf 'Types: deb-src\nURIs: http://deb.debian.org/debian\nSuites: %s\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
    "$(. /etc/os-release && echo "${VERSION_CODENAME:-bookworm}")" \
    | $SUDO tee /etc/apt/sources.list.d/artibus-deb-src.sources >/dev/null
  $SUDO apt-get update -qq
fi

if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
stamp=".venv/.artibus-installed"
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
  echo "setup: installing the artibus package and its Python dependencies into .venv"
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -e '.[test]'
  touch "$stamp"
fi

# the Windows 64-bit DLLs first (mingw-w64), packed by the linux build into binaries/win64
bash scripts/build_win64.sh build-win64
# the 64-bit ARM Linux binaries (Debian's aarch64 cross compilers, tested under qemu-user), packed into binaries/aarch64-linux
bash scripts/build_aarch64.sh build-aarch64
# SUNDIALS built optimised (Debian's static libraries are compiled without
# optimisation), once, into build-sundials/ (scripts/build_sundials.sh, about a minute)
bash scripts/build_sundials.sh build-sundials
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DARTIBUS_WIN64_DIR="$PWD/build-win64/win64" \
  -DARTIBUS_AARCH64_DIR="$PWD/build-aarch64/aarch64-linux" \
  -DSUNDIALS_DIR="$PWD/build-sundials/sundials-install/lib/cmake/sundials" >/dev/null
cmake --build build -j"$(nproc)"
.venv/bin/artibus pack >/dev/null

# fmi-sim (crates.io), a second importer the tests run every FMU in. It needs a
# recent Rust toolchain (rustup's, not Debian 12's) and libclang; without them
# the tests that use it say so and are skipped. Built once per machine into the
# cache outside the clone ($ARTIBUS_CACHE, scripts/build_common.sh), linked as
# .tools/bin/fmi-sim.
. scripts/build_common.sh        # CACHE
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

# the Modelica Reference-FMUs (FMI 2.0), a test set of FMUs made by others
# (tests/test_reference_fmus.py): built from their sources in the crate fmi-sys
# (crates.io) once per machine into the cache, linked as .tools/reference-fmus/
bash scripts/build_reference_fmus.sh || echo "setup: the Reference-FMUs could not be built; their tests will be skipped"

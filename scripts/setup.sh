#!/usr/bin/env bash
# What the main job (./run.sh) needs on a Debian machine, then the build:
#   apt packages (compiler, CMake, Eigen, Python venv, dpkg-dev for SUNDIALS' source),
#   a Python venv in .venv with the artibus package (pyproject.toml),
#   SUNDIALS built optimised (scripts/build_sundials.sh, cached outside the clone),
#   every FMU built into fmus/ with its linux64 binary, the benches packed.
# With --all-platforms also the cross-built binaries, packed into every FMU:
#   win64 (mingw-w64, scripts/build_win64.sh), aarch64-linux (Debian's aarch64 cross
#   compilers, scripts/build_aarch64.sh, tested under qemu-user); an FMU packed
#   already is packed again only when a binary of it changed.
# With --toolchains only the cross compilers' apt packages besides: ./run.sh builds the
#   cross binaries beside the rest, then packs them with --all-platforms.
# With --packages-only: the apt packages and the deb-src entry, nothing else (./run.sh,
#   before it starts the cross builds).
# With --platforms-built: --all-platforms packing the cross builds as they are, without
#   running them again (./run.sh, which has just run them).
# The test tools (Wine, fmi-sim, Chromium, the test extras) come from
# scripts/setup_test.sh, which ./test.sh runs (and which runs this with --all-platforms).
# Each step prints what it builds and roughly how long it takes; safe to run
# again: it installs and builds only what is missing or out of date.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/build_common.sh        # CACHE, step

ALL_PLATFORMS=0
TOOLCHAINS=0
PACKAGES_ONLY=0
CROSS_BUILD=1
for a in "$@"; do
  case "$a" in
    --all-platforms) ALL_PLATFORMS=1 TOOLCHAINS=1 ;;
    --toolchains) TOOLCHAINS=1 ;;
    --packages-only) PACKAGES_ONLY=1 ;;
    --platforms-built) ALL_PLATFORMS=1 TOOLCHAINS=1 CROSS_BUILD=0 ;;
    *) echo "usage: scripts/setup.sh [--all-platforms | --toolchains | --platforms-built] [--packages-only]" >&2; exit 2 ;;
  esac
done

# what the main job needs; the cross toolchains only with --all-platforms. Not
# libsundials-dev: SUNDIALS is built from Debian's source (scripts/build_sundials.sh),
# and the binary package pulls in MPI, PETSc and hypre (some 450 MB of downloads)
APT_PACKAGES="cmake make g++ libeigen3-dev python3 python3-venv python3-pip dpkg-dev"
# the cross compilers: mingw-w64's x86_64 C/C++ (win32 threads, as the alternatives pick when
# both are there; not the metapackage mingw-w64, whose i686 and posix compilers are some 175 MB
# more) and Debian's aarch64 ones (qemu-user, which runs them in the tests: setup_test.sh)
PLATFORM_APT_PACKAGES="g++-mingw-w64-x86-64-win32 gcc-aarch64-linux-gnu g++-aarch64-linux-gnu libc6-dev-arm64-cross"
[ "$TOOLCHAINS" = 1 ] && APT_PACKAGES="$APT_PACKAGES $PLATFORM_APT_PACKAGES"
apt_install $APT_PACKAGES

# Debian's source packages, for SUNDIALS built optimised (scripts/build_sundials.sh):
# a deb-src entry for this release's main, once
if ! grep -rqsE '^(deb-src|Types:.*deb-src)' /etc/apt/sources.list /etc/apt/sources.list.d/; then
  echo "setup: adding a deb-src entry (Debian's source packages, for SUNDIALS' source)"
  printf 'Types: deb-src\nURIs: http://deb.debian.org/debian\nSuites: %s\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
    "$(. /etc/os-release && echo "${VERSION_CODENAME:-bookworm}")" \
    | $SUDO tee /etc/apt/sources.list.d/artibus-deb-src.sources >/dev/null
  $SUDO apt-get update -qq
fi
[ "$PACKAGES_ONLY" = 1 ] && exit 0

# SUNDIALS built optimised (Debian's static libraries are compiled without
# optimisation), once per machine into the cache, linked as build-sundials/;
# in the background while pip installs the Python packages (one waits for the network,
# the other for the compiler)
sundials_log="$(mktemp)"
if [ -f "$(readlink -f build-sundials/sundials-install 2>/dev/null)/.artibus-complete" ]; then
  sundials_pid=""
else
  echo "setup: building SUNDIALS (CVODE, ARKODE; static, optimised) into $CACHE, once per machine (about 1 min), beside the Python packages"
  bash scripts/build_sundials.sh build-sundials >"$sundials_log" 2>&1 &
  sundials_pid=$!
fi

if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
stamp=".venv/.artibus-installed"
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
  # with the docs extra: the README's `mkdocs build` and the notebook under `jupyter nbconvert`
  step "installing the artibus package and its Python dependencies into .venv (about 1 min)" \
    .venv/bin/python -m pip install -q -e '.[docs]'
  touch "$stamp"
fi

if [ -n "$sundials_pid" ]; then
  if ! wait "$sundials_pid"; then cat "$sundials_log" >&2; rm -f "$sundials_log"; exit 1; fi
  echo "setup: SUNDIALS built"
fi
rm -f "$sundials_log"

# the cross-built binaries first, for the linux build to pack (binaries/win64)
platform_flags=()
if [ "$ALL_PLATFORMS" = 1 ]; then
  if [ "$CROSS_BUILD" = 1 ]; then
    step "building the win64 DLLs of every FMU with mingw-w64 (about 3 min the first time, SUNDIALS for win64 included)" \
      bash scripts/build_win64.sh build-win64
    step "building the aarch64-linux binaries of every FMU (about 3 min the first time, SUNDIALS for aarch64 included)" \
      bash scripts/build_aarch64.sh build-aarch64
  fi
  platform_flags+=(-DARTIBUS_WIN64_DIR="$PWD/build-win64/win64")
  platform_flags+=(-DARTIBUS_AARCH64_DIR="$PWD/build-aarch64/aarch64-linux")
fi
# (without --all-platforms the configured folders stay as they are: an FMU keeps
# binaries/win64 while its DLL is up to date, src/fmi/package_fmu.py drops a stale one)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${platform_flags[@]}" \
  -DSUNDIALS_DIR="$PWD/build-sundials/sundials-install/lib/cmake/sundials" >/dev/null
step "building the FMUs into fmus/ (about 1 min the first time on 2 cores)" \
  cmake --build build -j"$(nproc)"
.venv/bin/artibus pack >/dev/null
echo "setup: $(ls fmus/*.fmu | wc -l) FMUs and $(ls fmus/*.ssp | wc -l) benches in fmus/"

#!/usr/bin/env bash
# SUNDIALS built from Debian's source package (apt-get source, the version of
# the installed libsundials-dev), static, Release, position-independent, with
# only what the FMUs use: CVODE, ARKODE and the serial vector, dense matrix and
# dense linear solver. Debian's own static libraries are compiled without
# optimisation (-O0); BusDynamics spends a good part of its doStep in them.
# The one place that knows how to fetch and configure SUNDIALS: scripts/setup.sh
# calls it for the linux build, scripts/build_win64.sh for the win64 one.
#   build-sundials/src/       the source package, fetched once and shared
#   WORK_DIR/sundials-build/  the CMake build tree
#   WORK_DIR/sundials-install/  the install: WORK_DIR/sundials-install/lib/cmake/sundials
#                             is what -DSUNDIALS_DIR= takes
# Needs the apt package dpkg-dev and a deb-src entry (setup.sh adds them).
# Safe to run again: it builds only when the install lacks the stamp of the
# installed libsundials-dev's version.
# Usage: scripts/build_sundials.sh [WORK_DIR [extra CMake arguments]]
#        (default build-sundials; e.g. -DCMAKE_TOOLCHAIN_FILE=... for win64)
# Environment: ARTIBUS_SUNDIALS_JOBS (default 2) parallel compile jobs.
set -euo pipefail
. "$(dirname "$0")/build_common.sh"     # ROOT (the working directory), work_dir, quiet
W="$(work_dir "${1:-build-sundials}")"
[ $# -gt 0 ] && shift
JOBS="${ARTIBUS_SUNDIALS_JOBS:-2}"
QUIET_LOG="$W/sundials-step.log" QUIET_TAG=sundials

# 1. the source: the same Debian version as the installed libsundials-dev
ver="$(dpkg-query -W -f '${source:Version}' libsundials-dev)"
upstream="${ver#*:}"; upstream="${upstream%-*}"
srcdir="$ROOT/build-sundials/src/sundials-$upstream"
# (earlier versions of build_win64.sh fetched it into build-win64/src: reuse that)
[ ! -f "$srcdir/CMakeLists.txt" ] && [ -f "$ROOT/build-win64/src/sundials-$upstream/CMakeLists.txt" ] \
  && srcdir="$ROOT/build-win64/src/sundials-$upstream"
if [ ! -f "$srcdir/CMakeLists.txt" ]; then
  echo "sundials: fetching Debian's source package sundials $ver"
  mkdir -p "$ROOT/build-sundials/src"
  (cd "$ROOT/build-sundials/src" && quiet apt-get source -qq "sundials=$ver")
fi

# 2. built and installed, static and Release
inst="$W/sundials-install"
if [ ! -f "$inst/.artibus-$ver" ]; then
  echo "sundials: building SUNDIALS $upstream (static, Release) into $inst"
  rm -rf "$W/sundials-build" "$inst"
  quiet cmake -S "$srcdir" -B "$W/sundials-build" "$@" \
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$inst" \
    -DCMAKE_POSITION_INDEPENDENT_CODE=ON \
    -DBUILD_STATIC_LIBS=ON -DBUILD_SHARED_LIBS=OFF \
    -DBUILD_ARKODE=ON -DBUILD_CVODE=ON -DBUILD_CVODES=OFF -DBUILD_IDA=OFF \
    -DBUILD_IDAS=OFF -DBUILD_KINSOL=OFF -DBUILD_NVECTOR_MANYVECTOR=OFF \
    -DBUILD_FORTRAN_MODULE_INTERFACE=OFF -DBUILD_TESTING=OFF \
    -DEXAMPLES_ENABLE_C=OFF -DEXAMPLES_ENABLE_CXX=OFF -DEXAMPLES_INSTALL=OFF \
    -DSUNDIALS_PRECISION=double -DSUNDIALS_INDEX_SIZE=64
  quiet cmake --build "$W/sundials-build" -j"$JOBS"
  quiet cmake --install "$W/sundials-build"
  touch "$inst/.artibus-$ver"
fi

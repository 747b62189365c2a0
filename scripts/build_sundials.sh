#!/usr/bin/env bash
# SUNDIALS built from Debian's source package (apt-get source, the version of
# the installed libsundials-dev, else the one apt offers), static, Release, position-independent, with
# only what the FMUs use: CVODE, ARKODE and the serial vector, dense matrix and
# dense linear solver. Debian's own static libraries are compiled without
# optimisation (-O0); BusDynamics spends a good part of its doStep in them.
# The one place that knows how to fetch and configure SUNDIALS: scripts/setup.sh
# calls it for the linux build, scripts/build_win64.sh for the win64 one.
#
# A third-party build that does not change: it is cached outside the clone, in
# $ARTIBUS_CACHE (default ~/.cache/artibus, see build_common.sh), keyed by the
# SUNDIALS version, the configure flags, the toolchain file and the compiler, so
# a fresh clone on a machine that built it once reuses it:
#   $ARTIBUS_CACHE/src/sundials-VERSION/        the source package, fetched once
#   $ARTIBUS_CACHE/sundials/VERSION-KEY/        the install (.artibus-complete when whole)
#   WORK_DIR/sundials-install -> that install   what -DSUNDIALS_DIR=WORK_DIR/sundials-install/lib/cmake/sundials takes
# Concurrent builds of the same key wait for each other (flock).
# Needs the apt package dpkg-dev and a deb-src entry (setup.sh adds them).
# Usage: scripts/build_sundials.sh [WORK_DIR [extra CMake arguments]]
#        (default build-sundials; e.g. -DCMAKE_TOOLCHAIN_FILE=... for win64)
# Environment: ARTIBUS_SUNDIALS_JOBS (default 2) parallel compile jobs.
set -euo pipefail
. "$(dirname "$0")/build_common.sh"     # ROOT (the working directory), CACHE, work_dir, quiet, cache_key
W="$(work_dir "${1:-build-sundials}")"
[ $# -gt 0 ] && shift
JOBS="${ARTIBUS_SUNDIALS_JOBS:-2}"
QUIET_LOG="$W/sundials-step.log" QUIET_TAG=sundials

FLAGS=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_POSITION_INDEPENDENT_CODE=ON
  -DBUILD_STATIC_LIBS=ON -DBUILD_SHARED_LIBS=OFF
  -DBUILD_ARKODE=ON -DBUILD_CVODE=ON -DBUILD_CVODES=OFF -DBUILD_IDA=OFF
  -DBUILD_IDAS=OFF -DBUILD_KINSOL=OFF -DBUILD_NVECTOR_MANYVECTOR=OFF
  -DBUILD_FORTRAN_MODULE_INTERFACE=OFF -DBUILD_TESTING=OFF
  -DEXAMPLES_ENABLE_C=OFF -DEXAMPLES_ENABLE_CXX=OFF -DEXAMPLES_INSTALL=OFF
  -DSUNDIALS_PRECISION=double -DSUNDIALS_INDEX_SIZE=64 "$@")

# 1. the source: the same Debian version as the installed libsundials-dev, or, where it is
# not installed (the set-up does not need it: it pulls in MPI, PETSc and hypre, some 450 MB),
# the version apt would install; once per machine
ver="$(dpkg-query -W -f '${source:Version}' libsundials-dev 2>/dev/null || true)"
[ -n "$ver" ] || ver="$(apt-cache policy libsundials-dev | awk '/Candidate:/ {print $2}')"
case "$ver" in ""|"(none)") echo "sundials: no Debian package libsundials-dev known to apt (apt-get update?)" >&2; exit 1 ;; esac
upstream="${ver#*:}"; upstream="${upstream%-*}"
srcroot="$CACHE/src/sundials-$ver"
srcdir="$srcroot/sundials-$upstream"
mkdir -p "$CACHE/src"
(
  flock 9
  if [ ! -f "$srcroot/.artibus-complete" ]; then
    echo "sundials: fetching Debian's source package sundials $ver into $srcroot"
    rm -rf "$srcroot"; mkdir -p "$srcroot"
    (cd "$srcroot" && quiet apt-get source -qq "sundials=$ver")
    touch "$srcroot/.artibus-complete"
  fi
) 9>"$srcroot.lock"

# 2. built and installed, static and Release, once per key
key="$(cache_key "$ver" "${FLAGS[@]}")"
inst="$CACHE/sundials/$upstream-$key"
mkdir -p "$CACHE/sundials"
(
  flock 9
  if [ ! -f "$inst/.artibus-complete" ]; then
    echo "sundials: building SUNDIALS $upstream (static, Release) into $inst"
    tmp="$(mktemp -d "$CACHE/sundials/build.XXXXXX")"
    rm -rf "$inst"
    quiet cmake -S "$srcdir" -B "$tmp" "${FLAGS[@]}" -DCMAKE_INSTALL_PREFIX="$inst"
    quiet cmake --build "$tmp" -j"$JOBS"
    quiet cmake --install "$tmp"
    rm -rf "$tmp"
    touch "$inst/.artibus-complete"
  fi
) 9>"$inst.lock"

# 3. the clone's link to it (an install left by an older version of this script is replaced)
if [ "$(readlink "$W/sundials-install" 2>/dev/null)" != "$inst" ]; then
  rm -rf "$W/sundials-install"
  ln -s "$inst" "$W/sundials-install"
fi

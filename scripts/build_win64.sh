#!/usr/bin/env bash
# The Windows 64-bit binaries of every FMU, cross-compiled with Debian's
# mingw-w64 (cmake/mingw-w64.cmake), into build-win64/:
#   src/                  Debian's SUNDIALS source package (apt-get source, the
#                         version of the installed libsundials-dev)
#   sundials-install/     SUNDIALS built static for win64 (CVODE, ARKODE and the
#                         serial vector, dense matrix and dense solver they use)
#   win64/<Name>.dll      every FMU's binary; scripts/setup.sh packs them into
#                         binaries/win64 of each FMU (-DARTIBUS_WIN64_DIR)
#   fmu_check_<Name>.exe  the C importer (tests/c/fmu_check.c) for Wine
#   wineprefix/           the Wine prefix tests/test_win64.py runs it in
# Needs the apt packages mingw-w64, dpkg-dev and wine64 and a deb-src entry
# (setup.sh installs them). Safe to run again: it does only what is missing or out of date.
# Usage: scripts/build_win64.sh [BUILD_DIR]   (default build-win64)
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT="$PWD"
B="${1:-build-win64}"
case "$B" in /*) ;; *) B="$ROOT/$B" ;; esac
JOBS="${ARTIBUS_WIN64_JOBS:-2}"
mkdir -p "$B/src"
# run quietly; on failure show the end of the output
quiet() {
  local log="$B/last-step.log"
  "$@" >"$log" 2>&1 || { tail -40 "$log" >&2; echo "win64: failed: $*" >&2; return 1; }
}

# 1. SUNDIALS's source: the same Debian version as the linux build's libsundials-dev
ver="$(dpkg-query -W -f '${source:Version}' libsundials-dev)"
upstream="${ver#*:}"; upstream="${upstream%-*}"
srcdir="$B/src/sundials-$upstream"
if [ ! -f "$srcdir/CMakeLists.txt" ]; then
  echo "win64: fetching Debian's source package sundials $ver"
  (cd "$B/src" && quiet apt-get source -qq "sundials=$ver")
fi

# 2. SUNDIALS, static, for win64
inst="$B/sundials-install"
if [ ! -f "$inst/.artibus-$ver" ]; then
  echo "win64: building SUNDIALS $upstream (static, mingw-w64) into $inst"
  rm -rf "$B/sundials-build" "$inst"
  quiet cmake -S "$srcdir" -B "$B/sundials-build" \
    -DCMAKE_TOOLCHAIN_FILE="$ROOT/cmake/mingw-w64.cmake" \
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$inst" \
    -DBUILD_STATIC_LIBS=ON -DBUILD_SHARED_LIBS=OFF \
    -DBUILD_ARKODE=ON -DBUILD_CVODE=ON -DBUILD_CVODES=OFF -DBUILD_IDA=OFF \
    -DBUILD_IDAS=OFF -DBUILD_KINSOL=OFF -DBUILD_NVECTOR_MANYVECTOR=OFF \
    -DBUILD_FORTRAN_MODULE_INTERFACE=OFF -DBUILD_TESTING=OFF \
    -DEXAMPLES_ENABLE_C=OFF -DEXAMPLES_ENABLE_CXX=OFF -DEXAMPLES_INSTALL=OFF \
    -DSUNDIALS_PRECISION=double -DSUNDIALS_INDEX_SIZE=64
  quiet cmake --build "$B/sundials-build" -j"$JOBS"
  quiet cmake --install "$B/sundials-build"
  touch "$inst/.artibus-$ver"
fi

# 3. every FMU's DLL and its importer, from the same CMakeLists.txt
if [ ! -f "$B/CMakeCache.txt" ]; then
  quiet cmake -S . -B "$B" -DCMAKE_TOOLCHAIN_FILE="$ROOT/cmake/mingw-w64.cmake" \
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_FIND_ROOT_PATH="$inst" \
    -DSUNDIALS_DIR="$inst/lib/cmake/sundials" \
    -DEIGEN3_INCLUDE_DIR=/usr/include/eigen3   # Debian's libeigen3-dev (header-only)
fi
# only the FMUs and their importers (each fmu_check_<Name> needs its <Name>)
targets="$(sed -n 's/^add_fmu(\([A-Za-z0-9_]*\).*/fmu_check_\1/p' CMakeLists.txt)"
quiet cmake --build "$B" -j"$JOBS" --target $targets
echo "win64: $(ls "$B"/win64/*.dll | wc -l) DLLs in $B/win64"

# 4. a Wine prefix for tests/test_win64.py (Debian's wine64 package), made once
wine="$(command -v wine64 || command -v wine || true)"
[ -z "$wine" ] && [ -x /usr/lib/wine/wine64 ] && wine=/usr/lib/wine/wine64
if [ -n "$wine" ] && [ ! -f "$B/wineprefix/system.reg" ]; then
  echo "win64: creating the Wine prefix $B/wineprefix (once, about 30 s)"
  WINEPREFIX="$B/wineprefix" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml=" \
    quiet "$wine" wineboot --init
fi

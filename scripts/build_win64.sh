#!/usr/bin/env bash
# The Windows 64-bit binaries of every FMU, cross-compiled with Debian's
# mingw-w64 (cmake/mingw-w64.cmake), into build-win64/:
#   sundials-install/     SUNDIALS built static for win64 (CVODE, ARKODE and the
#                         serial vector, dense matrix and dense solver they use) by
#                         scripts/build_sundials.sh from Debian's source package
#                         (the version of the installed libsundials-dev): a link
#                         into the cache outside the clone ($ARTIBUS_CACHE)
#   win64/<Name>.dll      every FMU's binary; scripts/setup.sh packs them into
#                         binaries/win64 of each FMU (-DARTIBUS_WIN64_DIR)
#   win64/fmi3/<Name>.dll the FMI 3.0 build's, packed into binaries/x86_64-windows of
#                         fmus/fmi3/<Name>.fmu (unless the build has ARTIBUS_FMI3=OFF)
#   fmu_check_<Name>.exe  the C importer (tests/c/fmu_check.c) for Wine
#   wineprefix/           the Wine prefix tests/test_win64.py runs it in: a link to
#                         $ARTIBUS_CACHE/wineprefix-<Wine version>, made once per machine
# Needs the apt packages g++-mingw-w64-x86-64-win32, dpkg-dev (and wine64 for the tests) and a deb-src entry
# (setup.sh installs them). Safe to run again: it does only what is missing or out of date.
# Usage: scripts/build_win64.sh [BUILD_DIR]   (default build-win64)
set -euo pipefail
. "$(dirname "$0")/build_common.sh"     # ROOT (the working directory), work_dir, quiet
B="$(work_dir "${1:-build-win64}")"
JOBS="${ARTIBUS_WIN64_JOBS:-2}"
QUIET_LOG="$B/last-step.log" QUIET_TAG=win64

# 1.-2. SUNDIALS, static, for win64 (scripts/build_sundials.sh: Debian's source
# package, the linux build's version), then every FMU's DLL and its importer
# (build_common.sh's cross_build)
cross_build "$B" mingw-w64.cmake x86_64-w64-mingw32-gcc "$JOBS"
echo "win64: $(ls "$B"/win64/*.dll | wc -l) DLLs in $B/win64"

# 3. a Wine prefix for tests/test_win64.py (Debian's wine64 package), made once
# per machine and Wine version in the cache, linked from the build directory
# (not with ARTIBUS_CROSS_IMPORTERS=0: no importer for Wine to run)
[ "${ARTIBUS_CROSS_IMPORTERS:-1}" = 0 ] && exit 0
wine="$(command -v wine64 || command -v wine || true)"
[ -z "$wine" ] && [ -x /usr/lib/wine/wine64 ] && wine=/usr/lib/wine/wine64
if [ -n "$wine" ]; then
  prefix="$CACHE/wineprefix-$("$wine" --version 2>/dev/null | tr -c 'A-Za-z0-9.\n' '_' | head -1)"
  (
    flock 9
    if [ ! -f "$prefix/.artibus-complete" ]; then
      echo "win64: creating the Wine prefix $prefix (once, about 30 s)"
      rm -rf "$prefix"
      WINEPREFIX="$prefix" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml=" \
        quiet "$wine" wineboot --init
      touch "$prefix/.artibus-complete"
    fi
  ) 9>"$prefix.lock"
  if [ "$(readlink "$B/wineprefix" 2>/dev/null)" != "$prefix" ]; then
    rm -rf "$B/wineprefix"
    ln -s "$prefix" "$B/wineprefix"
  fi
fi

#!/usr/bin/env bash
# The 64-bit ARM Linux binaries of every FMU, cross-compiled with Debian's
# gcc-aarch64-linux-gnu / g++-aarch64-linux-gnu (cmake/aarch64-linux.cmake), into
# build-aarch64/:
#   sundials-install/         SUNDIALS built static for aarch64 (CVODE, ARKODE and the
#                             serial vector, dense matrix and dense solver they use) by
#                             scripts/build_sundials.sh from Debian's source package
#                             (the version of the installed libsundials-dev): a link
#                             into the cache outside the clone ($ARTIBUS_CACHE)
#   aarch64-linux/<Name>.so   every FMU's binary (libstdc++ and libgcc linked in: it
#                             needs only the C library); the linux build packs them into
#                             binaries/aarch64-linux of each FMU (-DARTIBUS_AARCH64_DIR)
#   fmu_check_<Name>          the C importer (tests/c/fmu_check.c) for qemu-user
#   fmu/<Name>/               an FMU tree with binaries/aarch64-linux for that importer
# tests/test_aarch64.py runs the importers under qemu-aarch64 -L /usr/aarch64-linux-gnu.
# Needs the apt packages below (setup.sh installs them) and, for SUNDIALS, dpkg-dev
# and a deb-src entry. Safe to run again: it does only what is missing or out of date.
# Usage: scripts/build_aarch64.sh [BUILD_DIR]   (default build-aarch64)
# Environment: ARTIBUS_AARCH64_JOBS (default 2) parallel compile jobs.
set -euo pipefail
. "$(dirname "$0")/build_common.sh"     # ROOT (the working directory), work_dir, quiet
APT_PACKAGES="gcc-aarch64-linux-gnu g++-aarch64-linux-gnu libc6-dev-arm64-cross"   # (qemu-user: the tests', setup_test.sh)
B="$(work_dir "${1:-build-aarch64}")"
JOBS="${ARTIBUS_AARCH64_JOBS:-2}"
QUIET_LOG="$B/last-step.log" QUIET_TAG=aarch64

# 0. the cross compilers, when missing
missing=""
for p in $APT_PACKAGES; do
  dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"
done
if [ -n "$missing" ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "aarch64: installing$missing"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi

# 1.-2. SUNDIALS, static, for aarch64 (scripts/build_sundials.sh: Debian's source
# package, the linux build's version), without fused multiply-add as the FMUs
# (cmake/aarch64-linux.cmake), then every FMU's shared object and its importer
# (build_common.sh's cross_build)
cross_build "$B" aarch64-linux.cmake aarch64-linux-gnu-gcc "$JOBS"
echo "aarch64: $(ls "$B"/aarch64-linux/*.so | wc -l) shared objects in $B/aarch64-linux"

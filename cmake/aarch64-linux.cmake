# Cross-compiling for 64-bit ARM Linux with Debian's gcc-aarch64-linux-gnu and
# g++-aarch64-linux-gnu (the aarch64 C library from libc6-dev-arm64-cross):
#   cmake -S . -B build-aarch64 -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-linux.cmake
# scripts/build_aarch64.sh does this (and builds SUNDIALS for it first).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(ARTIBUS_CROSS_PREFIX aarch64-linux-gnu)

set(CMAKE_C_COMPILER ${ARTIBUS_CROSS_PREFIX}-gcc)
set(CMAKE_CXX_COMPILER ${ARTIBUS_CROSS_PREFIX}-g++)

# No fused multiply-add: GCC contracts a*b+c into one fmadd on aarch64 by default
# (x86-64's baseline has no FMA instruction, so the linux64 build never does); with
# contraction off both builds round every product and sum alike, and the aarch64
# results equal the x86_64 ones (tests/test_aarch64.py)
set(CMAKE_C_FLAGS_INIT "-ffp-contract=off")
set(CMAKE_CXX_FLAGS_INIT "-ffp-contract=off")

# headers and libraries of the target only from the cross sysroot (and the
# prefixes given in CMAKE_FIND_ROOT_PATH, e.g. the cross-built SUNDIALS);
# programs (Python) from the host
set(CMAKE_FIND_ROOT_PATH /usr/${ARTIBUS_CROSS_PREFIX} ${CMAKE_FIND_ROOT_PATH})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# the test programs (tests/c/fmu_check.c) run under qemu-user (Debian's qemu-user)
# with the aarch64 C library of libc6-arm64-cross
find_program(ARTIBUS_QEMU NAMES qemu-aarch64 qemu-aarch64-static NO_CMAKE_FIND_ROOT_PATH)
if(ARTIBUS_QEMU)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${ARTIBUS_QEMU} -L /usr/${ARTIBUS_CROSS_PREFIX})
endif()

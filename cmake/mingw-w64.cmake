# Cross-compiling for 64-bit Windows with Debian's mingw-w64 (package mingw-w64):
#   cmake -S . -B build-win64 -DCMAKE_TOOLCHAIN_FILE=cmake/mingw-w64.cmake
# scripts/build_win64.sh does this (and builds SUNDIALS for it first).
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR x86_64)
set(ARTIBUS_MINGW_PREFIX x86_64-w64-mingw32)

set(CMAKE_C_COMPILER ${ARTIBUS_MINGW_PREFIX}-gcc)
set(CMAKE_CXX_COMPILER ${ARTIBUS_MINGW_PREFIX}-g++)
set(CMAKE_RC_COMPILER ${ARTIBUS_MINGW_PREFIX}-windres)

# headers and libraries of the target only from the mingw sysroot (and the
# prefixes given in CMAKE_FIND_ROOT_PATH, e.g. the cross-built SUNDIALS);
# programs (Python) from the host
set(CMAKE_FIND_ROOT_PATH /usr/${ARTIBUS_MINGW_PREFIX} ${CMAKE_FIND_ROOT_PATH})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# the test programs (tests/c/fmu_check.c) run under Wine
find_program(ARTIBUS_WINE NAMES wine64 wine PATHS /usr/lib/wine NO_CMAKE_FIND_ROOT_PATH)
if(ARTIBUS_WINE)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${ARTIBUS_WINE})
endif()

/* The test programs' one way to open an FMU's binary and find its functions: dlopen/dlsym on
 * Linux, LoadLibrary/GetProcAddress in the win64 builds run under Wine (scripts/build_win64.sh).
 * LOAD(path) gives the library or NULL; SYM(lib, name) the function's address or NULL. */
#ifndef ARTIBUS_TESTS_DYNLOAD_H
#define ARTIBUS_TESTS_DYNLOAD_H

#ifdef _WIN32
#include <windows.h>
#define LOAD(path) ((void *)LoadLibraryA(path))
#define SYM(lib, name) ((void *)GetProcAddress((HMODULE)(lib), name))
#else
#include <dlfcn.h>
#define LOAD(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define SYM(lib, name) dlsym(lib, name)
#endif

#endif

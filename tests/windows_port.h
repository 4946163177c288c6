/* windows_port.h - the few POSIX calls the tests make, for their Windows
   builds (mingw-w64, run under wine by tests/run_windows.sh): force-included
   with -include, so the tests' sources stay as they are. Only what the
   Windows tier's programs use. */
#ifndef HAIROBB_TESTS_WINDOWS_PORT_H
#define HAIROBB_TESTS_WINDOWS_PORT_H
#ifdef _WIN32
#include <direct.h>
#include <errno.h>
#include <io.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* 64-bit Windows' malloc returns 16-byte aligned blocks, freed with free()
   as posix_memalign's are; the tests ask for 16 bytes at most. */
static inline int posix_memalign(void **block, size_t alignment, size_t size)
{
    if (alignment > 16) return EINVAL;
    *block = malloc(size);
    return *block ? 0 : ENOMEM;
}

static inline char *mkdtemp(char *path_template)
{
    return _mktemp(path_template) && _mkdir(path_template) == 0 ? path_template : NULL;
}

#define mkdir(path, mode) _mkdir(path)
#define popen _popen
#define pclose _pclose
#endif
#endif

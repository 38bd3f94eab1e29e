/* dlopen, dlsym, dlclose and dlerror for the C hosts (host.c, FMI 2.0; host3.c, FMI 3.0): the
 * POSIX ones on Linux, the same names on LoadLibraryA & co. with MinGW for Windows (the tests
 * run those hosts under wine). Included after <stdio.h>. */
#ifndef RUSTFMU_HOST_DL_H
#define RUSTFMU_HOST_DL_H
#ifdef _WIN32
/* Windows (MinGW, run under wine in the tests): the same host, dlopen & co. on LoadLibraryA. */
#include <windows.h>
#define RTLD_NOW 0
#define RTLD_LOCAL 0
static char dl_error[64];
static void *dlopen(const char *path, int flags) {
    (void)flags;
    void *h = (void *)LoadLibraryA(path);
    if (!h) snprintf(dl_error, sizeof dl_error, "LoadLibraryA failed, error %lu", (unsigned long)GetLastError());
    return h;
}
static void *dlsym(void *lib, const char *name) { return (void *)GetProcAddress((HMODULE)lib, name); }
static int dlclose(void *lib) {
    if (FreeLibrary((HMODULE)lib)) return 0;
    snprintf(dl_error, sizeof dl_error, "FreeLibrary failed, error %lu", (unsigned long)GetLastError());
    return 1;
}
static const char *dlerror(void) { return dl_error; }
#else
#include <dlfcn.h>
#endif
#endif

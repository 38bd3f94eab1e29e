/* An FMU binary that misbehaves on purpose, for the tests of the runner's crash isolation.
 * Compiled with -DMODE=<n>: fmi2Instantiate then
 *   1  dereferences NULL (SIGSEGV),
 *   2  prints to stderr and aborts (SIGABRT),
 *   3  hangs,
 *   4  works (returns NULL with a logged reason), and the library's destructor segfaults when
 *      the process unloads it (a crash after the check has its result).
 * Every other function answers fmi2Error. */
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#ifndef MODE
#error "compile with -DMODE=1..4"
#endif

typedef void *C;
typedef unsigned int Status;
typedef struct {
    void (*logger)(void *, const char *, Status, const char *, const char *, ...);
    void *allocateMemory, *freeMemory, *stepFinished;
    void *componentEnvironment;
} Callbacks;

const char *fmi2GetTypesPlatform(void) { return "default"; }
const char *fmi2GetVersion(void) { return "2.0"; }

C fmi2Instantiate(const char *name, int type, const char *guid, const char *res, const Callbacks *cb, int visible,
                  int logging) {
    (void)type, (void)guid, (void)res, (void)visible, (void)logging;
    switch (MODE) {
    case 1: {
        volatile int *volatile p = NULL;
        *p = 1;
        break;
    }
    case 2:
        fprintf(stderr, "bad FMU: giving up with abort()\n");
        abort();
    case 3:
        for (;;) pause();
    default:
        break;
    }
    if (cb && cb->logger) cb->logger(cb->componentEnvironment, name, 3, "logStatusError", "%s", "never instantiates");
    return NULL;
}

#if MODE == 4
/* A real fault (not raise(): a Rust host's SIGSEGV handler returns from a raised one). */
__attribute__((destructor)) static void crash_on_unload(void) {
    volatile int *volatile p = NULL;
    *p = 4;
}
#endif

void fmi2FreeInstance(C c) { (void)c; }

#define REFUSE(f) \
    Status f() { return 3; }
REFUSE(fmi2SetDebugLogging)
REFUSE(fmi2SetupExperiment)
REFUSE(fmi2EnterInitializationMode)
REFUSE(fmi2ExitInitializationMode)
REFUSE(fmi2Terminate)
REFUSE(fmi2Reset)
REFUSE(fmi2GetReal)
REFUSE(fmi2GetInteger)
REFUSE(fmi2GetBoolean)
REFUSE(fmi2GetString)
REFUSE(fmi2SetReal)
REFUSE(fmi2SetInteger)
REFUSE(fmi2SetBoolean)
REFUSE(fmi2SetString)
REFUSE(fmi2GetFMUstate)
REFUSE(fmi2SetFMUstate)
REFUSE(fmi2FreeFMUstate)
REFUSE(fmi2SerializedFMUstateSize)
REFUSE(fmi2SerializeFMUstate)
REFUSE(fmi2DeSerializeFMUstate)
REFUSE(fmi2GetDirectionalDerivative)
REFUSE(fmi2SetRealInputDerivatives)
REFUSE(fmi2GetRealOutputDerivatives)
REFUSE(fmi2DoStep)
REFUSE(fmi2CancelStep)
REFUSE(fmi2GetStatus)
REFUSE(fmi2GetRealStatus)
REFUSE(fmi2GetIntegerStatus)
REFUSE(fmi2GetBooleanStatus)
REFUSE(fmi2GetStringStatus)

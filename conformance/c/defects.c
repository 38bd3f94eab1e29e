/* Deliberately defective FMU binaries: the fixtures of tests/defective_fmus.rs, which prove that
 * the suite still catches what it is for ("proof that it still bites", issue 51).
 *
 * Why a shim and not a model of our own in C: a fixture's good variant must pass every check
 * (else a failure would not prove the defect), and a from-scratch C FMU that passes the whole
 * suite (every call in every state, refusals with messages, FMU state, model exchange,
 * directional derivatives, FMI 2.0 and 3.0) would be thousands of lines to keep right. This file
 * is a pass-through instead: it loads a conformant binary (INNER, the path of a copy of this
 * workspace's Dahlquist, der(x) = -k x, FMI 2.0 and 3.0 in one library) and forwards
 * every fmi2 and fmi3 function to it, except the one a `-DDEFECT_...` flag breaks. Without a
 * flag it is the good variant. Each defect is one violation, written here in a few lines:
 *
 *   DEFECT_GET_PAST         fmi2GetReal / fmi3GetFloat64 write one value past nValues
 *   DEFECT_STEP_STUCK       fmi2DoStep / fmi3DoStep answer OK without advancing time
 *   DEFECT_STATE_OVERRUN    fmi2SerializeFMUstate / fmi3SerializeFMUState write 16 bytes past
 *                           the size fmi2SerializedFMUstateSize / fmi3SerializedFMUStateSize
 *                           announced
 *   DEFECT_ME_EQUATIONS     model exchange's derivatives are twice co-simulation's
 *   DEFECT_RESTORE          fmi2SetFMUstate / fmi3SetFMUState answer OK and restore nothing
 *   DEFECT_FREE_CRASH       fmi2FreeInstance / fmi3FreeInstance crash (SIGSEGV)
 *   DEFECT_ONE_PAST         fmi2GetRealStatus / fmi3GetNumberOfContinuousStates write a second
 *                           value after the one their output pointer holds
 *   DEFECT_TOKEN=\"...\"    the binary does not check the GUID / instantiationToken: it
 *                           instantiates with the given one whatever the importer passes
 *   DEFECT_EMPTY_REFUSED    fmi2GetInteger / fmi3GetFloat64 refuse a call of no values with NULL
 *                           arrays (legal: the arrays have n = 0 elements)
 *   DEFECT_NULL_COMPONENT   fmi2DoStep answers OK on a NULL component
 *   DEFECT_STATUS_KIND      fmi2GetBooleanStatus answers OK for a kind that is not its own
 *   DEFECT_LOGGING          fmi3SetDebugLogging accepts a category the description does not declare
 *   DEFECT_PROBES           answers the probes of an importer's mistakes otherwise than the model
 *                           it wraps: fmi*OK for NULL arrays and outputs (fmi2GetDerivatives,
 *                           fmi2SetContinuousStates, fmi2CompletedIntegratorStep,
 *                           fmi2NewDiscreteStates, fmi3GetContinuousStateDerivatives,
 *                           fmi3DeserializeFMUState, a NULL seed of fmi3GetDirectionalDerivative,
 *                           fmi2SetContinuousStates on a NULL component),
 *                           for fmi3GetInt32 of any variable (Dahlquist has no Int32) and for
 *                           fmi3GetContinuousStates of another nContinuousStates; fmi3Discard for
 *                           fmi3DoStep with NULL outputs; fmi2Error for fmi2GetFMUstate into an
 *                           existing state (legal: FMI 2.0.5 §2.1.8); a crash in
 *                           fmi2FreeInstance(NULL) (a no-op by FMI 2.0.5 §2.1.5)
 *
 * The forwarding functions are two instructions of x86-64 assembly each (a jump through the
 * address looked up in the inner library): they pass every argument on, whatever the
 * signature, so no signature is written twice. Linux x86-64 only, like the test. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define HIDDEN __attribute__((visibility("hidden")))

/* X(name) for every function forwarded; the broken ones are defined below instead. */
#define FMI2_COMMON(X)                                                                                            \
    X(fmi2GetTypesPlatform) X(fmi2GetVersion) X(fmi2SetDebugLogging) X(fmi2SetupExperiment)                       \
    X(fmi2EnterInitializationMode) X(fmi2ExitInitializationMode) X(fmi2Terminate) X(fmi2Reset)                    \
    X(fmi2GetBoolean) X(fmi2GetString) X(fmi2SetReal) X(fmi2SetInteger) X(fmi2SetBoolean)        \
    X(fmi2SetString) X(fmi2FreeFMUstate) X(fmi2SerializedFMUstateSize)                          \
    X(fmi2DeSerializeFMUstate) X(fmi2GetDirectionalDerivative) X(fmi2SetRealInputDerivatives)                     \
    X(fmi2GetRealOutputDerivatives) X(fmi2CancelStep) X(fmi2GetStatus)                                            \
    X(fmi2GetIntegerStatus) X(fmi2GetStringStatus) X(fmi2EnterEventMode)                  \
    X(fmi2EnterContinuousTimeMode) X(fmi2SetTime)         \
    X(fmi2GetEventIndicators) X(fmi2GetContinuousStates)                               \
    X(fmi2GetNominalsOfContinuousStates)

#define FMI3_COMMON(X)                                                                                            \
    X(fmi3GetVersion) X(fmi3InstantiateScheduledExecution) X(fmi3EnterInitializationMode)  \
    X(fmi3ExitInitializationMode) X(fmi3EnterEventMode) X(fmi3Terminate) X(fmi3Reset) X(fmi3GetFloat32)           \
    X(fmi3GetInt8) X(fmi3GetUInt8) X(fmi3GetInt16) X(fmi3GetUInt16) X(fmi3GetUInt32)               \
    X(fmi3GetInt64) X(fmi3GetUInt64) X(fmi3GetBoolean) X(fmi3GetString) X(fmi3GetBinary) X(fmi3GetClock)           \
    X(fmi3SetFloat32) X(fmi3SetFloat64) X(fmi3SetInt8) X(fmi3SetUInt8) X(fmi3SetInt16) X(fmi3SetUInt16)           \
    X(fmi3SetInt32) X(fmi3SetUInt32) X(fmi3SetInt64) X(fmi3SetUInt64) X(fmi3SetBoolean) X(fmi3SetString)           \
    X(fmi3SetBinary) X(fmi3SetClock) X(fmi3GetNumberOfVariableDependencies) X(fmi3GetVariableDependencies)        \
    X(fmi3GetFMUState) X(fmi3FreeFMUState) X(fmi3SerializedFMUStateSize)                \
    X(fmi3GetAdjointDerivative) X(fmi3EnterConfigurationMode)                     \
    X(fmi3ExitConfigurationMode) X(fmi3GetIntervalDecimal) X(fmi3GetIntervalFraction) X(fmi3GetShiftDecimal)      \
    X(fmi3GetShiftFraction) X(fmi3SetIntervalDecimal) X(fmi3SetIntervalFraction) X(fmi3SetShiftDecimal)           \
    X(fmi3SetShiftFraction) X(fmi3EvaluateDiscreteStates) X(fmi3UpdateDiscreteStates)                             \
    X(fmi3EnterContinuousTimeMode) X(fmi3CompletedIntegratorStep) X(fmi3SetTime) X(fmi3SetContinuousStates)       \
    X(fmi3GetEventIndicators) X(fmi3GetNominalsOfContinuousStates)                     \
    X(fmi3GetNumberOfEventIndicators) X(fmi3EnterStepMode)                                                        \
    X(fmi3GetOutputDerivatives) X(fmi3ActivateModelPartition)

/* The functions a defect may break: forwarded like the others where its defect is not compiled
 * in, and always reachable through next_<name> for the broken version to call. */
#define BREAKABLE(X)                                                                                              \
    X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2GetReal) X(fmi2DoStep) X(fmi2SerializeFMUstate)                  \
    X(fmi2SetFMUstate) X(fmi2GetDerivatives) X(fmi3InstantiateModelExchange) X(fmi3InstantiateCoSimulation)       \
    X(fmi3FreeInstance) X(fmi3GetFloat64) X(fmi3DoStep) X(fmi3SerializeFMUState) X(fmi3SetFMUState)               \
    X(fmi3GetContinuousStateDerivatives) X(fmi2GetRealStatus) X(fmi3GetNumberOfContinuousStates)                  \
    X(fmi2GetInteger) X(fmi2GetBooleanStatus) X(fmi3SetDebugLogging) X(fmi2GetFMUstate)                          \
    X(fmi2CompletedIntegratorStep) X(fmi2NewDiscreteStates) X(fmi2SetContinuousStates) X(fmi3GetInt32)            \
    X(fmi3DeserializeFMUState) X(fmi3GetDirectionalDerivative) X(fmi3GetContinuousStates)

#define POINTER(f) HIDDEN void *next_##f;
FMI2_COMMON(POINTER)
FMI3_COMMON(POINTER)
BREAKABLE(POINTER)

#define TRAMPOLINE(f)                                                                                             \
    __asm__(".text\n.globl " #f "\n.type " #f ",@function\n" #f ":\n\tjmp *next_" #f "(%rip)\n.size " #f ",.-" #f  \
            "\n");
FMI2_COMMON(TRAMPOLINE)
FMI3_COMMON(TRAMPOLINE)

#ifndef DEFECT_TOKEN
TRAMPOLINE(fmi2Instantiate)
TRAMPOLINE(fmi3InstantiateModelExchange)
TRAMPOLINE(fmi3InstantiateCoSimulation)
#endif
#if !defined(DEFECT_FREE_CRASH) && !defined(DEFECT_PROBES)
TRAMPOLINE(fmi2FreeInstance)
#endif
#ifndef DEFECT_FREE_CRASH
TRAMPOLINE(fmi3FreeInstance)
#endif
#ifndef DEFECT_PROBES
TRAMPOLINE(fmi2GetFMUstate)
TRAMPOLINE(fmi2CompletedIntegratorStep)
TRAMPOLINE(fmi2NewDiscreteStates)
TRAMPOLINE(fmi2SetContinuousStates)
TRAMPOLINE(fmi3GetInt32)
TRAMPOLINE(fmi3DeserializeFMUState)
TRAMPOLINE(fmi3GetDirectionalDerivative)
TRAMPOLINE(fmi3GetContinuousStates)
#endif
#ifndef DEFECT_GET_PAST
TRAMPOLINE(fmi2GetReal)
#endif
#if !defined(DEFECT_GET_PAST) && !defined(DEFECT_EMPTY_REFUSED)
TRAMPOLINE(fmi3GetFloat64)
#endif
#ifndef DEFECT_EMPTY_REFUSED
TRAMPOLINE(fmi2GetInteger)
#endif
#if !defined(DEFECT_STEP_STUCK) && !defined(DEFECT_NULL_COMPONENT)
TRAMPOLINE(fmi2DoStep)
#endif
#if !defined(DEFECT_STEP_STUCK) && !defined(DEFECT_PROBES)
TRAMPOLINE(fmi3DoStep)
#endif
#ifndef DEFECT_STATUS_KIND
TRAMPOLINE(fmi2GetBooleanStatus)
#endif
#ifndef DEFECT_LOGGING
TRAMPOLINE(fmi3SetDebugLogging)
#endif
#ifndef DEFECT_STATE_OVERRUN
TRAMPOLINE(fmi2SerializeFMUstate)
TRAMPOLINE(fmi3SerializeFMUState)
#endif
#ifndef DEFECT_RESTORE
TRAMPOLINE(fmi2SetFMUstate)
TRAMPOLINE(fmi3SetFMUState)
#endif
#ifndef DEFECT_ONE_PAST
TRAMPOLINE(fmi2GetRealStatus)
TRAMPOLINE(fmi3GetNumberOfContinuousStates)
#endif
#if !defined(DEFECT_ME_EQUATIONS) && !defined(DEFECT_PROBES)
TRAMPOLINE(fmi2GetDerivatives)
TRAMPOLINE(fmi3GetContinuousStateDerivatives)
#endif

static void *inner;

/* Loads INNER (an absolute path, given at compile time: a copy of this library made elsewhere,
 * as the unload check makes, still finds it) and looks up every function. */
__attribute__((constructor)) static void load_inner(void) {
    inner = dlopen(INNER, RTLD_NOW | RTLD_LOCAL);
    if (!inner) {
        fprintf(stderr, "defects.c: %s\n", dlerror());
        abort();
    }
#define LOOKUP(f)                                                                                                 \
    if (!(next_##f = dlsym(inner, #f))) {                                                                         \
        fprintf(stderr, "defects.c: %s has no %s\n", INNER, #f);                                                 \
        abort();                                                                                                  \
    }
    FMI2_COMMON(LOOKUP)
    FMI3_COMMON(LOOKUP)
    BREAKABLE(LOOKUP)
}

/* Unloaded with this library, so that unloading the FMU unloads the model too. */
__attribute__((destructor)) static void unload_inner(void) {
    if (inner) dlclose(inner);
}

typedef int S; /* fmi2Status and fmi3Status: a C enum, 0 is OK */

#ifdef DEFECT_TOKEN
void *fmi2Instantiate(const char *name, int type, const char *guid, const char *res, const void *cb, int visible,
                      int logging) {
    (void)guid;
    return ((void *(*)(const char *, int, const char *, const char *, const void *, int, int))next_fmi2Instantiate)(
        name, type, DEFECT_TOKEN, res, cb, visible, logging);
}
void *fmi3InstantiateModelExchange(const char *name, const char *token, const char *res, bool visible,
                                   bool logging, void *env, void *log) {
    (void)token;
    return ((void *(*)(const char *, const char *, const char *, bool, bool, void *,
                       void *))next_fmi3InstantiateModelExchange)(name, DEFECT_TOKEN, res, visible, logging, env, log);
}
void *fmi3InstantiateCoSimulation(const char *name, const char *token, const char *res, bool visible, bool logging,
                                  bool eventMode, bool early, const unsigned *vrs, size_t n, void *env, void *log,
                                  void *update) {
    (void)token;
    return ((void *(*)(const char *, const char *, const char *, bool, bool, bool, bool, const unsigned *, size_t,
                       void *, void *, void *))next_fmi3InstantiateCoSimulation)(
        name, DEFECT_TOKEN, res, visible, logging, eventMode, early, vrs, n, env, log, update);
}
#endif

#ifdef DEFECT_FREE_CRASH
static void crash(void *instance) {
    volatile int *volatile nowhere = NULL;
    if (instance) *nowhere = 1; /* SIGSEGV, as a use of freed memory would */
}
void fmi2FreeInstance(void *c) {
    ((void (*)(void *))next_fmi2FreeInstance)(c);
    crash(c);
}
void fmi3FreeInstance(void *c) {
    ((void (*)(void *))next_fmi3FreeInstance)(c);
    crash(c);
}
#endif

#ifdef DEFECT_GET_PAST
S fmi2GetReal(void *c, const unsigned *vr, size_t n, double *value) {
    S s = ((S(*)(void *, const unsigned *, size_t, double *))next_fmi2GetReal)(c, vr, n, value);
    if (s == 0 && n > 0) value[n] = value[0];
    return s;
}
S fmi3GetFloat64(void *c, const unsigned *vr, size_t nvr, double *values, size_t n) {
    S s = ((S(*)(void *, const unsigned *, size_t, double *, size_t))next_fmi3GetFloat64)(c, vr, nvr, values, n);
    if (s == 0 && n > 0) values[n] = values[0];
    return s;
}
#endif

#ifdef DEFECT_STEP_STUCK
S fmi2DoStep(void *c, double t, double h, int noSetPrior) {
    (void)c, (void)t, (void)h, (void)noSetPrior;
    return 0;
}
S fmi3DoStep(void *c, double t, double h, bool noSetPrior, bool *eventHandlingNeeded, bool *terminate,
             bool *earlyReturn, double *lastSuccessfulTime) {
    (void)c, (void)noSetPrior;
    *eventHandlingNeeded = *terminate = *earlyReturn = false;
    *lastSuccessfulTime = t + h;
    return 0;
}
#endif

#ifdef DEFECT_STATE_OVERRUN
S fmi2SerializeFMUstate(void *c, void *state, unsigned char *bytes, size_t size) {
    S s = ((S(*)(void *, void *, unsigned char *, size_t))next_fmi2SerializeFMUstate)(c, state, bytes, size);
    if (s == 0) memset(bytes + size, 0xA5, 16);
    return s;
}
S fmi3SerializeFMUState(void *c, void *state, unsigned char *bytes, size_t size) {
    S s = ((S(*)(void *, void *, unsigned char *, size_t))next_fmi3SerializeFMUState)(c, state, bytes, size);
    if (s == 0) memset(bytes + size, 0xA5, 16);
    return s;
}
#endif

#ifdef DEFECT_RESTORE
S fmi2SetFMUstate(void *c, void *state) {
    (void)c, (void)state;
    return 0;
}
S fmi3SetFMUState(void *c, void *state) {
    (void)c, (void)state;
    return 0;
}
#endif

#ifdef DEFECT_ME_EQUATIONS
static S doubled(S s, double *d, size_t n) {
    for (size_t i = 0; s == 0 && i < n; i++) d[i] *= 2;
    return s;
}
S fmi2GetDerivatives(void *c, double *d, size_t n) {
    return doubled(((S(*)(void *, double *, size_t))next_fmi2GetDerivatives)(c, d, n), d, n);
}
S fmi3GetContinuousStateDerivatives(void *c, double *d, size_t n) {
    return doubled(((S(*)(void *, double *, size_t))next_fmi3GetContinuousStateDerivatives)(c, d, n), d, n);
}
#endif

#ifdef DEFECT_ONE_PAST
S fmi2GetRealStatus(void *c, int kind, double *value) {
    S s = ((S(*)(void *, int, double *))next_fmi2GetRealStatus)(c, kind, value);
    if (s == 0) value[1] = value[0];
    return s;
}
S fmi3GetNumberOfContinuousStates(void *c, size_t *n) {
    S s = ((S(*)(void *, size_t *))next_fmi3GetNumberOfContinuousStates)(c, n);
    if (s == 0) n[1] = n[0];
    return s;
}
#endif

#ifdef DEFECT_EMPTY_REFUSED
S fmi2GetInteger(void *c, const unsigned *vr, size_t n, int *value) {
    if (n == 0) return 3; /* fmi2Error */
    return ((S(*)(void *, const unsigned *, size_t, int *))next_fmi2GetInteger)(c, vr, n, value);
}
S fmi3GetFloat64(void *c, const unsigned *vr, size_t nvr, double *values, size_t n) {
    if (nvr == 0 && n == 0) return 3; /* fmi3Error */
    return ((S(*)(void *, const unsigned *, size_t, double *, size_t))next_fmi3GetFloat64)(c, vr, nvr, values, n);
}
#endif

#ifdef DEFECT_NULL_COMPONENT
S fmi2DoStep(void *c, double t, double h, int noSetPrior) {
    if (!c) return 0;
    return ((S(*)(void *, double, double, int))next_fmi2DoStep)(c, t, h, noSetPrior);
}
#endif

#ifdef DEFECT_STATUS_KIND
S fmi2GetBooleanStatus(void *c, int kind, int *value) {
    S s = ((S(*)(void *, int, int *))next_fmi2GetBooleanStatus)(c, kind, value);
    return s == 2 ? 0 : s; /* fmi2Discard answered as fmi2OK */
}
#endif

#ifdef DEFECT_LOGGING
S fmi3SetDebugLogging(void *c, bool on, size_t n, const char *const *categories) {
    S s = ((S(*)(void *, bool, size_t, const char *const *))next_fmi3SetDebugLogging)(c, on, n, categories);
    return n == 1 && categories && s == 3 ? 0 : s; /* an unknown category's fmi3Error answered as fmi3OK */
}
#endif

#ifdef DEFECT_PROBES
S fmi2GetDerivatives(void *c, double *d, size_t n) {
    if (!d) return 0;
    return ((S(*)(void *, double *, size_t))next_fmi2GetDerivatives)(c, d, n);
}
S fmi2SetContinuousStates(void *c, const double *x, size_t n) {
    if (!x || !c) return 0; /* NULL states, or a NULL component, accepted */
    return ((S(*)(void *, const double *, size_t))next_fmi2SetContinuousStates)(c, x, n);
}
S fmi2CompletedIntegratorStep(void *c, int noSetPrior, int *enter, int *terminate) {
    if (!enter || !terminate) return 0;
    return ((S(*)(void *, int, int *, int *))next_fmi2CompletedIntegratorStep)(c, noSetPrior, enter, terminate);
}
S fmi2NewDiscreteStates(void *c, void *eventInfo) {
    if (!eventInfo) return 0;
    return ((S(*)(void *, void *))next_fmi2NewDiscreteStates)(c, eventInfo);
}
S fmi2GetFMUstate(void *c, void **state) {
    if (state && *state) return 3; /* fmi2Error: an existing state is not overwritten */
    return ((S(*)(void *, void **))next_fmi2GetFMUstate)(c, state);
}
void fmi2FreeInstance(void *c) {
    volatile int *volatile nowhere = NULL;
    if (!c) *nowhere = 1; /* SIGSEGV */
    ((void (*)(void *))next_fmi2FreeInstance)(c);
}
S fmi3GetContinuousStateDerivatives(void *c, double *d, size_t n) {
    if (!d) return 0;
    return ((S(*)(void *, double *, size_t))next_fmi3GetContinuousStateDerivatives)(c, d, n);
}
S fmi3GetContinuousStates(void *c, double *x, size_t n) {
    size_t nx = 0;
    S s = ((S(*)(void *, size_t *))next_fmi3GetNumberOfContinuousStates)(c, &nx);
    if (s == 0 && n != nx) return 0; /* another nContinuousStates accepted, nothing written */
    return ((S(*)(void *, double *, size_t))next_fmi3GetContinuousStates)(c, x, n);
}
S fmi3DeserializeFMUState(void *c, const unsigned char *bytes, size_t size, void **state) {
    if (!bytes) return 0;
    return ((S(*)(void *, const unsigned char *, size_t, void **))next_fmi3DeserializeFMUState)(c, bytes, size, state);
}
S fmi3GetInt32(void *c, const unsigned *vr, size_t nvr, int *values, size_t n) {
    (void)c, (void)vr, (void)nvr;
    for (size_t i = 0; values && i < n; i++) values[i] = 0;
    return 0; /* any value reference, whatever its type */
}
S fmi3GetDirectionalDerivative(void *c, const unsigned *unknowns, size_t nUnknowns, const unsigned *knowns,
                               size_t nKnowns, const double *seed, size_t nSeed, double *sensitivity,
                               size_t nSensitivity) {
    if (!seed) return 0;
    return ((S(*)(void *, const unsigned *, size_t, const unsigned *, size_t, const double *, size_t, double *,
                  size_t))next_fmi3GetDirectionalDerivative)(c, unknowns, nUnknowns, knowns, nKnowns, seed, nSeed,
                                                             sensitivity, nSensitivity);
}
S fmi3DoStep(void *c, double t, double h, bool noSetPrior, bool *eventHandlingNeeded, bool *terminate,
             bool *earlyReturn, double *lastSuccessfulTime) {
    if (!eventHandlingNeeded || !terminate || !earlyReturn || !lastSuccessfulTime) return 2; /* fmi3Discard */
    return ((S(*)(void *, double, double, bool, bool *, bool *, bool *, double *))next_fmi3DoStep)(
        c, t, h, noSetPrior, eventHandlingNeeded, terminate, earlyReturn, lastSuccessfulTime);
}
#endif

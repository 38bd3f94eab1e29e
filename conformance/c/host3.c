/* A minimal FMI 3.0 host in plain C: loads an FMU binary with dlopen, runs it through
 * Co-Simulation (and Model Exchange where it has continuous states to integrate), frees it and
 * dlcloses, so that valgrind memcheck sees a whole run.
 *
 * Usage: host3 <binary.so> <instantiationToken> <resourcePath> <steps> <h> <nStates|-1> <vr[:n],vr[:n],...> [vr=value[,value...] ...]
 *   CS: instantiate, set the given Float64 values, initialize at t = 0, <steps> fmi3DoStep of
 *   <h> (checking lastSuccessfulTime and the flags), read the listed Float64s, terminate, free.
 *   An array counts its elements (FMI 3.0: nValues is every element): `vr:n` reads n values of
 *   vr, `vr=a,b,c` sets three; nStates is every element of the state arrays.
 *   ME (nStates >= 0): instantiate, set the values, initialize, event iteration, then <steps>
 *   explicit-Euler steps of <h> through fmi3GetContinuousStates / Derivatives / SetTime /
 *   SetContinuousStates / CompletedIntegratorStep, terminate, free.
 * Prints "final <hex bit patterns>" (CS) and "me-final <hex bit patterns>" (ME). Exits 1 with a
 * reason on stderr on any failure. With HOST_TRACE set, also "trace <step> <hex bit patterns>"
 * after every co-simulation step. With HOST_EVENT_MODE set (an FMU with clocks, which requires
 * it), Co-Simulation runs with eventModeUsed: Event Mode after initialization and after a step
 * that needs it is passed with fmi3UpdateDiscreteStates and fmi3EnterStepMode (no clock activated).
 * Builds for Linux (dlopen) or, with MinGW, for Windows
 * (LoadLibraryA). */
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf (%zu, %llx) from MinGW, not msvcrt's */
#endif
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "dl.h" /* dlopen & co., on Linux and Windows */

typedef void *fmi3Instance;
typedef uint32_t fmi3ValueReference;
typedef enum { fmi3OK, fmi3Warning, fmi3Discard, fmi3Error, fmi3Fatal } fmi3Status;
typedef void (*fmi3LogMessageCallback)(void *, fmi3Status, const char *, const char *);

static int messages = 0;
static char last[1024];

static void logger(void *env, fmi3Status status, const char *category, const char *message) {
    if (env != (void *)&messages) {
        fprintf(stderr, "logger: wrong instanceEnvironment %p\n", env);
        exit(1);
    }
    snprintf(last, sizeof last, "%s", message ? message : "(null)");
    messages++;
    if (getenv("HOST_VERBOSE")) fprintf(stderr, "[%d %s] %s\n", status, category ? category : "(null)", last);
}

#define LOAD(type, var, name)                                          \
    type var = (type)dlsym(lib, name);                                 \
    if (!var) { fprintf(stderr, "missing %s\n", name); return 1; }
#define CHECK(call)                                                    \
    do {                                                               \
        fmi3Status s_ = (call);                                        \
        if (s_ != fmi3OK) {                                            \
            fprintf(stderr, "%s -> %d: %s\n", #call, s_, last);        \
            return 1;                                                  \
        }                                                              \
    } while (0)

typedef fmi3Instance (*InstantiateCS)(const char *, const char *, const char *, bool, bool, bool, bool,
                                      const fmi3ValueReference *, size_t, void *, fmi3LogMessageCallback, void *);
typedef fmi3Instance (*InstantiateME)(const char *, const char *, const char *, bool, bool, void *,
                                      fmi3LogMessageCallback);
typedef void (*FreeInstance)(fmi3Instance);
typedef fmi3Status (*EnterInit)(fmi3Instance, bool, double, double, bool, double);
typedef fmi3Status (*Unary)(fmi3Instance);
typedef fmi3Status (*GetF64)(fmi3Instance, const fmi3ValueReference *, size_t, double *, size_t);
typedef fmi3Status (*SetF64)(fmi3Instance, const fmi3ValueReference *, size_t, const double *, size_t);
typedef fmi3Status (*DoStep)(fmi3Instance, double, double, bool, bool *, bool *, bool *, double *);
typedef fmi3Status (*Update)(fmi3Instance, bool *, bool *, bool *, bool *, bool *, double *);
typedef fmi3Status (*Vector)(fmi3Instance, double *, size_t);
typedef fmi3Status (*SetVector)(fmi3Instance, const double *, size_t);
typedef fmi3Status (*SetTime)(fmi3Instance, double);
typedef fmi3Status (*Completed)(fmi3Instance, bool, bool *, bool *);
typedef fmi3Status (*Count)(fmi3Instance, size_t *);

/* "vr[:n],vr[:n],...": the value references, and the number of values they hold (n, else 1). */
static size_t parse_vrs(const char *list, fmi3ValueReference **out, size_t *values) {
    size_t n = 0, cap = 16;
    *out = malloc(cap * sizeof **out);
    *values = 0;
    const char *p = list;
    while (*p) {
        char *end;
        unsigned long v = strtoul(p, &end, 10);
        if (end == p) break;
        unsigned long count = 1;
        if (*end == ':') {
            const char *q = end + 1;
            count = strtoul(q, &end, 10);
            if (end == q) break;
        }
        if (n == cap) *out = realloc(*out, (cap *= 2) * sizeof **out);
        (*out)[n++] = (fmi3ValueReference)v;
        *values += count;
        p = *end == ',' ? end + 1 : end;
    }
    return n;
}

static void print_bits(const char *tag, const double *v, size_t n) {
    printf("%s", tag);
    for (size_t i = 0; i < n; i++) {
        uint64_t b;
        memcpy(&b, &v[i], sizeof b);
        printf(" %llx", (unsigned long long)b);
    }
    printf("\n");
}

/* Whether the FMU's lastSuccessfulTime is the end of the step: FMI 3.0.2 (fmi3DoStep) lets it
 * deviate from currentCommunicationPoint + communicationStepSize by rounding (the FMU may add up
 * its time otherwise than this host does), so within a millionth of the step, not bit for bit. */
static int same_time(double reached, double end, double h) {
    double d = reached - end;
    return (d < 0 ? -d : d) <= 1e-6 * h;
}

int main(int argc, char **argv) {
    if (argc < 8) {
        fprintf(stderr, "usage: host3 <so> <token> <resourcePath> <steps> <h> <nStates|-1> <vrs> [vr=value...]\n");
        return 2;
    }
    const char *token = argv[2], *res = argv[3];
    int steps = atoi(argv[4]);
    double h = atof(argv[5]);
    long nx = atol(argv[6]);
    fmi3ValueReference *vrs;
    size_t nv_values = 0;
    size_t nv = parse_vrs(argv[7], &vrs, &nv_values);
    double *values = calloc(nv_values ? nv_values : 1, sizeof *values);
    int nset = argc - 8;
    fmi3ValueReference *set_vrs = calloc(nset ? nset : 1, sizeof *set_vrs);
    size_t nset_values = 0, set_cap = 16;
    double *set_vals = calloc(set_cap, sizeof *set_vals);
    for (int i = 0; i < nset; i++) {
        char *eq = strchr(argv[8 + i], '=');
        if (!eq) { fprintf(stderr, "bad vr=value: %s\n", argv[8 + i]); return 2; }
        set_vrs[i] = (fmi3ValueReference)strtoul(argv[8 + i], NULL, 10);
        const char *p = eq + 1;
        for (;;) {
            char *end;
            double x = strtod(p, &end);
            if (end == p) { fprintf(stderr, "bad vr=value: %s\n", argv[8 + i]); return 2; }
            if (nset_values == set_cap) set_vals = realloc(set_vals, (set_cap *= 2) * sizeof *set_vals);
            set_vals[nset_values++] = x;
            if (*end != ',') break;
            p = end + 1;
        }
    }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 1; }
    LOAD(InstantiateCS, instantiate_cs, "fmi3InstantiateCoSimulation");
    LOAD(InstantiateME, instantiate_me, "fmi3InstantiateModelExchange");
    LOAD(FreeInstance, free_instance, "fmi3FreeInstance");
    LOAD(EnterInit, enter_init, "fmi3EnterInitializationMode");
    LOAD(Unary, exit_init, "fmi3ExitInitializationMode");
    LOAD(Unary, terminate, "fmi3Terminate");
    LOAD(GetF64, get_f64, "fmi3GetFloat64");
    LOAD(SetF64, set_f64, "fmi3SetFloat64");
    LOAD(DoStep, do_step, "fmi3DoStep");
    LOAD(Update, update, "fmi3UpdateDiscreteStates");
    LOAD(Unary, enter_ctm, "fmi3EnterContinuousTimeMode");
    LOAD(Unary, enter_event_mode, "fmi3EnterEventMode");
    LOAD(Unary, enter_step_mode, "fmi3EnterStepMode");
    LOAD(Vector, get_x, "fmi3GetContinuousStates");
    LOAD(Vector, get_dx, "fmi3GetContinuousStateDerivatives");
    LOAD(SetVector, set_x, "fmi3SetContinuousStates");
    LOAD(SetTime, set_time, "fmi3SetTime");
    LOAD(Completed, completed, "fmi3CompletedIntegratorStep");
    LOAD(Count, n_states, "fmi3GetNumberOfContinuousStates");

    /* Co-Simulation */
    bool event_mode = getenv("HOST_EVENT_MODE") != NULL;
    fmi3Instance c = instantiate_cs("host3", token, res, false, false, event_mode, false, NULL, 0, &messages, logger, NULL);
    if (!c) { fprintf(stderr, "fmi3InstantiateCoSimulation returned NULL: %s\n", last); return 1; }
    CHECK(set_f64(c, set_vrs, nset, set_vals, nset_values));
    CHECK(enter_init(c, false, 0.0, 0.0, false, 0.0));
    CHECK(exit_init(c));
    if (event_mode) {
        bool need = true, term = false, nom = false, vals = false, next_defined = false;
        double next = 0.0;
        for (int k = 0; need && k < 100; k++) CHECK(update(c, &need, &term, &nom, &vals, &next_defined, &next));
        CHECK(enter_step_mode(c));
    }
    double t = 0.0;
    int trace = getenv("HOST_TRACE") != NULL, time_noted = 0;
    for (int i = 0; i < steps; i++) {
        bool event = true, term = true, early = true;
        double reached = -1.0;
        CHECK(do_step(c, t, h, true, &event, &term, &early, &reached));
        if (event_mode && event && !term && !early && same_time(reached, t + h, h)) {
            bool need = true, term2 = false, nom = false, vals = false, next_defined = false;
            double next = 0.0;
            CHECK(enter_event_mode(c));
            for (int k = 0; need && k < 100; k++) CHECK(update(c, &need, &term2, &nom, &vals, &next_defined, &next));
            CHECK(enter_step_mode(c));
            event = false;
        }
        if (event || term || early) {
            fprintf(stderr, "fmi3DoStep at %g: event %d terminate %d early %d lastSuccessfulTime %g\n", t, event, term, early, reached);
            return 1;
        }
        /* A step that answered fmi3OK without early return but ended elsewhere: noted (once), and
         * the run goes on, so that valgrind sees every call; the check reports it. */
        if (!same_time(reached, t + h, h) && !time_noted) {
            fprintf(stderr, "lastSuccessfulTime: fmi3DoStep(%.17g, %.17g) answered fmi3OK without early return and lastSuccessfulTime %.17g\n", t, h, reached);
            time_noted = 1;
        }
        t += h;
        CHECK(get_f64(c, vrs, nv, values, nv_values));
        if (trace) {
            char tag[32];
            snprintf(tag, sizeof tag, "trace %d", i);
            print_bits(tag, values, nv_values);
        }
    }
    print_bits("final", values, nv_values);
    CHECK(terminate(c));
    free_instance(c);

    /* Model Exchange: explicit Euler */
    if (nx >= 0) {
        fmi3Instance m = instantiate_me("host3me", token, res, false, false, &messages, logger);
        if (!m) { fprintf(stderr, "fmi3InstantiateModelExchange returned NULL: %s\n", last); return 1; }
        size_t n = 0;
        CHECK(n_states(m, &n));
        if ((long)n != nx) { fprintf(stderr, "fmi3GetNumberOfContinuousStates: %zu, expected %ld\n", n, nx); return 1; }
        double *x = calloc(n ? n : 1, sizeof *x), *dx = calloc(n ? n : 1, sizeof *dx);
        CHECK(set_f64(m, set_vrs, nset, set_vals, nset_values));
        CHECK(enter_init(m, false, 0.0, 0.0, false, 0.0));
        CHECK(exit_init(m));
        bool need = true, term = false, nom = false, vals = false, next_defined = false;
        double next = 0.0;
        for (int k = 0; need && k < 100; k++) CHECK(update(m, &need, &term, &nom, &vals, &next_defined, &next));
        CHECK(enter_ctm(m));
        t = 0.0;
        for (int i = 0; i < steps; i++) {
            CHECK(get_x(m, x, n));
            CHECK(get_dx(m, dx, n));
            for (size_t j = 0; j < n; j++) x[j] += h * dx[j];
            t += h;
            CHECK(set_time(m, t));
            CHECK(set_x(m, x, n));
            bool enter = false, stop = false;
            CHECK(completed(m, true, &enter, &stop));
            if (stop) { fprintf(stderr, "terminateSimulation at %g\n", t); return 1; }
            if (enter) {
                CHECK(enter_event_mode(m));
                need = true;
                for (int k = 0; need && k < 100; k++) CHECK(update(m, &need, &term, &nom, &vals, &next_defined, &next));
                CHECK(enter_ctm(m));
            }
        }
        CHECK(get_f64(m, vrs, nv, values, nv_values));
        print_bits("me-final", values, nv_values);
        CHECK(terminate(m));
        free_instance(m);
        free(x);
        free(dx);
    }
    printf("messages %d\n", messages);
    free(vrs);
    free(values);
    free(set_vrs);
    free(set_vals);
    if (dlclose(lib) != 0) { fprintf(stderr, "dlclose: %s\n", dlerror()); return 1; }
    return 0;
}

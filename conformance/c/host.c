/* A minimal FMI 2.0 co-simulation host in plain C: proves an FMU runs in a process that is
 * neither Python nor Rust, and gives valgrind a whole run to check.
 *
 * Usage: host <binary.so> <guid> <resourceURI> <steps> <h> <vr,vr,...> [vr=value ...]
 *   Loads the binary with dlopen, sets the given Real values, initializes at t = 0, makes
 *   <steps> steps of <h>, reading the listed Real value references after each; saves the FMU
 *   state halfway, serializes and restores it and checks the second half repeats bit for bit;
 *   resets and checks a rerun repeats bit for bit; makes refused calls whose messages contain
 *   '%' (the logger formats with vsnprintf, as C hosts do); frees everything and dlcloses.
 * Prints "final <hex bit patterns of the last values>" and "messages <n>"; exits 1 with a
 * reason on stderr on any failure. With HOST_FOREIGN set (another exporter's FMU), the checks
 * of this exporter's conventions are left out.
 * With HOST_ME="<nx>,<ni>,<steps>,<h>" it also runs the FMU through Model Exchange: a new
 * instance, the same Real values set, initialization and the event iteration, then <steps>
 * explicit-Euler steps of <h> (time, state and step events handled as an importer must), and
 * prints "me-final <hex bit patterns of the listed values>".
 * With HOST_TRACE set it also prints "trace <step> <hex bit patterns>" for every co-simulation
 * step of the last run (the whole trajectory, to compare binaries of two platforms).
 * Builds with any C compiler for Linux (dlopen) or, with MinGW, for Windows (LoadLibraryA). */
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf (%zu, %llx) from MinGW, not msvcrt's */
#endif
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "dl.h" /* dlopen & co., on Linux and Windows */

typedef void *fmi2Component;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef int fmi2Boolean;
typedef const char *fmi2String;
typedef char fmi2Byte;
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef struct {
    void (*logger)(void *, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, fmi2Status);
    void *componentEnvironment;
} fmi2CallbackFunctions;

static int messages = 0;
static char last[1024];

static void logger(void *env, fmi2String name, fmi2Status status, fmi2String category, fmi2String message, ...) {
    va_list args;
    va_start(args, message);
    vsnprintf(last, sizeof last, message, args); /* printf rules, as the standard says */
    va_end(args);
    if (env != (void *)&messages) {
        fprintf(stderr, "logger: wrong componentEnvironment %p\n", env);
        exit(1);
    }
    messages++;
    if (getenv("HOST_VERBOSE")) fprintf(stderr, "[%s %d %s] %s\n", name, status, category, last);
}

#define LOAD(type, var, name)                                         \
    type var = (type)dlsym(lib, name);                                \
    if (!var) { fprintf(stderr, "missing %s\n", name); return 1; }
#define CHECK(call)                                                   \
    do {                                                              \
        fmi2Status s_ = (call);                                       \
        if (s_ != fmi2OK) {                                           \
            fprintf(stderr, "%s -> %d: %s\n", #call, s_, last);       \
            return 1;                                                 \
        }                                                             \
    } while (0)

typedef fmi2Component (*Instantiate)(fmi2String, fmi2Type, fmi2String, fmi2String, const fmi2CallbackFunctions *,
                                     fmi2Boolean, fmi2Boolean);
typedef void (*FreeInstance)(fmi2Component);
typedef fmi2Status (*Setup)(fmi2Component, fmi2Boolean, double, double, fmi2Boolean, double);
typedef fmi2Status (*Unary)(fmi2Component);
typedef fmi2Status (*GetReal)(fmi2Component, const fmi2ValueReference *, size_t, double *);
typedef fmi2Status (*SetReal)(fmi2Component, const fmi2ValueReference *, size_t, const double *);
typedef fmi2Status (*DoStep)(fmi2Component, double, double, fmi2Boolean);
typedef fmi2Status (*GetState)(fmi2Component, fmi2FMUstate *);
typedef fmi2Status (*SetState)(fmi2Component, fmi2FMUstate);
typedef fmi2Status (*StateSize)(fmi2Component, fmi2FMUstate, size_t *);
typedef fmi2Status (*Serialize)(fmi2Component, fmi2FMUstate, fmi2Byte *, size_t);
typedef fmi2Status (*Deserialize)(fmi2Component, const fmi2Byte *, size_t, fmi2FMUstate *);
typedef fmi2Status (*DebugLogging)(fmi2Component, fmi2Boolean, size_t, const fmi2String *);
typedef struct {
    fmi2Boolean newDiscreteStatesNeeded, terminateSimulation, nominalsOfContinuousStatesChanged,
        valuesOfContinuousStatesChanged, nextEventTimeDefined;
    double nextEventTime;
} fmi2EventInfo;
typedef fmi2Status (*NewDiscreteStates)(fmi2Component, fmi2EventInfo *);
typedef fmi2Status (*Completed)(fmi2Component, fmi2Boolean, fmi2Boolean *, fmi2Boolean *);
typedef fmi2Status (*SetTime)(fmi2Component, double);
typedef fmi2Status (*SetVector)(fmi2Component, const double *, size_t);
typedef fmi2Status (*GetVector)(fmi2Component, double *, size_t);

/* The event iteration: fmi2NewDiscreteStates until no new discrete states are needed. */
static int event_iteration(NewDiscreteStates nds, fmi2Component c, fmi2EventInfo *info) {
    for (int k = 0; k < 100; k++) {
        if (nds(c, info) != fmi2OK) { fprintf(stderr, "fmi2NewDiscreteStates failed: %s\n", last); return 1; }
        if (info->terminateSimulation) { fprintf(stderr, "terminateSimulation\n"); return 1; }
        if (!info->newDiscreteStatesNeeded) return 0;
    }
    fprintf(stderr, "the event iteration does not end\n");
    return 1;
}

int main(int argc, char **argv) {
    if (argc < 7) {
        fprintf(stderr, "usage: host <binary.so> <guid> <resourceURI> <steps> <h> <vr,vr,...> [vr=value ...]\n");
        return 2;
    }
    int steps = atoi(argv[4]);
    double h = atof(argv[5]);
    fmi2ValueReference vrs[256];
    size_t nvr = 0;
    for (char *p = strtok(argv[6], ","); p && nvr < 256; p = strtok(NULL, ",")) vrs[nvr++] = (fmi2ValueReference)atoi(p);
    double *values = calloc(nvr, sizeof(double));
    double *trace = calloc((size_t)steps * nvr, sizeof(double));

    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 1; }
    LOAD(Instantiate, instantiate, "fmi2Instantiate");
    LOAD(FreeInstance, free_instance, "fmi2FreeInstance");
    LOAD(Setup, setup, "fmi2SetupExperiment");
    LOAD(Unary, enter, "fmi2EnterInitializationMode");
    LOAD(Unary, exit_init, "fmi2ExitInitializationMode");
    LOAD(Unary, terminate, "fmi2Terminate");
    LOAD(Unary, reset, "fmi2Reset");
    LOAD(GetReal, get_real, "fmi2GetReal");
    LOAD(SetReal, set_real, "fmi2SetReal");
    LOAD(DoStep, do_step, "fmi2DoStep");
    LOAD(GetState, get_state, "fmi2GetFMUstate");
    LOAD(SetState, set_state, "fmi2SetFMUstate");
    LOAD(GetState, free_state, "fmi2FreeFMUstate");
    LOAD(StateSize, state_size, "fmi2SerializedFMUstateSize");
    LOAD(Serialize, serialize, "fmi2SerializeFMUstate");
    LOAD(Deserialize, deserialize, "fmi2DeSerializeFMUstate");
    LOAD(DebugLogging, debug_logging, "fmi2SetDebugLogging");

    fmi2CallbackFunctions cb = {logger, NULL, NULL, NULL, &messages};
    fmi2Component c = instantiate("c-host %s %n", fmi2CoSimulation, argv[2], argv[3], &cb, 0, 1);
    if (!c) { fprintf(stderr, "fmi2Instantiate returned NULL: %s\n", last); return 1; }

    /* '%' in messages: a category name and a bad step; with "%s" as the format they are text. */
    /* (Not for another exporter's FMU, HOST_FOREIGN set: refusing an unknown category with a
     * message that names it is this exporter's convention.) */
    const char *bad[] = {"log%s%n%s%n"};
    if (!getenv("HOST_FOREIGN")) {
        if (debug_logging(c, 1, 1, bad) != fmi2Error) { fprintf(stderr, "unknown category accepted\n"); return 1; }
        if (!strstr(last, "log%s%n%s%n")) { fprintf(stderr, "the '%%' message arrived as: %s\n", last); return 1; }
    }

    /* A step of h < 0, refused with fmi2Error (and its message through the logger, with "%s"),
     * on an instance of its own: after fmi2Error the instance may only be freed or reset (FMI
     * 2.0.5 §2.1.3 and the state machine of §4.2.4), so it is freed here and the run below
     * uses another. Required of this exporter's FMUs; of another's (HOST_FOREIGN) the call is
     * only made, for valgrind to watch, since a step size < 0 is the importer's mistake. */
    {
        fmi2Component bad_step = instantiate("c-host-bad-step", fmi2CoSimulation, argv[2], argv[3], &cb, 0, 1);
        if (!bad_step) { fprintf(stderr, "fmi2Instantiate returned NULL: %s\n", last); return 1; }
        CHECK(setup(bad_step, 0, 0.0, 0.0, 0, 0.0));
        CHECK(enter(bad_step));
        CHECK(exit_init(bad_step));
        if (do_step(bad_step, 0.0, -1.0, 1) != fmi2Error && !getenv("HOST_FOREIGN")) {
            fprintf(stderr, "h < 0 accepted\n");
            return 1;
        }
        free_instance(bad_step);
    }

    for (int run = 0; run < 2; run++) {
        for (int i = 7; i < argc; i++) {
            fmi2ValueReference vr = (fmi2ValueReference)atoi(argv[i]);
            double v = atof(strchr(argv[i], '=') + 1);
            CHECK(set_real(c, &vr, 1, &v));
        }
        CHECK(setup(c, 0, 0.0, 0.0, 0, 0.0));
        CHECK(enter(c));
        CHECK(exit_init(c));
        fmi2FMUstate saved = NULL;
        for (int n = 0; n < steps; n++) {
            if (n == steps / 2) {
                /* save, serialize, deserialize: the copy is what the second half restarts from */
                size_t size = 0;
                fmi2FMUstate s = NULL;
                CHECK(get_state(c, &s));
                CHECK(state_size(c, s, &size));
                fmi2Byte *bytes = malloc(size);
                CHECK(serialize(c, s, bytes, size));
                CHECK(free_state(c, &s));
                CHECK(deserialize(c, bytes, size, &saved));
                free(bytes);
            }
            CHECK(do_step(c, n * h, h, 0));
            CHECK(get_real(c, vrs, nvr, trace + (size_t)n * nvr));
        }
        if (run == 0 && steps > 1) {
            /* back to the middle: the second half must repeat bit for bit */
            CHECK(set_state(c, saved));
            for (int n = steps / 2; n < steps; n++) {
                CHECK(do_step(c, n * h, h, 0));
                CHECK(get_real(c, vrs, nvr, values));
                if (memcmp(values, trace + (size_t)n * nvr, nvr * sizeof(double))) {
                    fprintf(stderr, "step %d differs after fmi2SetFMUstate\n", n);
                    return 1;
                }
            }
            memcpy(values, trace + (size_t)(steps - 1) * nvr, nvr * sizeof(double));
        } else if (steps > 0 && memcmp(values, trace + (size_t)(steps - 1) * nvr, nvr * sizeof(double))) {
            fprintf(stderr, "the run after fmi2Reset differs\n");
            return 1;
        }
        CHECK(free_state(c, &saved));
        CHECK(terminate(c));
        if (terminate(c) != fmi2Error) { fprintf(stderr, "second fmi2Terminate accepted\n"); return 1; }
        if (run == 0) CHECK(reset(c));
    }
    free_instance(c);
    free_instance(NULL);

    const char *me = getenv("HOST_ME");
    double *me_values = NULL;
    if (me) {
        int nx = 0, ni = 0, me_steps = 0;
        double me_h = 0;
        if (sscanf(me, "%d,%d,%d,%lf", &nx, &ni, &me_steps, &me_h) != 4) { fprintf(stderr, "HOST_ME: %s\n", me); return 2; }
        LOAD(Unary, enter_event_mode, "fmi2EnterEventMode");
        LOAD(NewDiscreteStates, new_discrete_states, "fmi2NewDiscreteStates");
        LOAD(Unary, enter_ct_mode, "fmi2EnterContinuousTimeMode");
        LOAD(Completed, completed, "fmi2CompletedIntegratorStep");
        LOAD(SetTime, set_time, "fmi2SetTime");
        LOAD(SetVector, set_states, "fmi2SetContinuousStates");
        LOAD(GetVector, get_states, "fmi2GetContinuousStates");
        LOAD(GetVector, get_derivatives, "fmi2GetDerivatives");
        LOAD(GetVector, get_indicators, "fmi2GetEventIndicators");
        double *x = calloc((size_t)nx + 1, sizeof(double)), *dx = calloc((size_t)nx + 1, sizeof(double));
        double *z = calloc((size_t)ni + 1, sizeof(double)), *z1 = calloc((size_t)ni + 1, sizeof(double));
        me_values = calloc(nvr + 1, sizeof(double));
        fmi2Component m = instantiate("c-host-me", fmi2ModelExchange, argv[2], argv[3], &cb, 0, 1);
        if (!m) { fprintf(stderr, "fmi2Instantiate(fmi2ModelExchange) returned NULL: %s\n", last); return 1; }
        for (int i = 7; i < argc; i++) {
            fmi2ValueReference vr = (fmi2ValueReference)atoi(argv[i]);
            double v = atof(strchr(argv[i], '=') + 1);
            CHECK(set_real(m, &vr, 1, &v));
        }
        CHECK(setup(m, 0, 0.0, 0.0, 0, 0.0));
        CHECK(enter(m));
        CHECK(exit_init(m));
        fmi2EventInfo info;
        if (event_iteration(new_discrete_states, m, &info)) return 1;
        CHECK(enter_ct_mode(m));
        int time_events = info.nextEventTimeDefined;
        double next_event = info.nextEventTime, t = 0.0;
        CHECK(get_indicators(m, z, (size_t)ni));
        for (int n = 0; n < me_steps; n++) {
            CHECK(get_states(m, x, (size_t)nx));
            CHECK(get_derivatives(m, dx, (size_t)nx));
            double t1 = t + me_h;
            int time_event = time_events && next_event <= t1;
            if (time_event) t1 = next_event > t ? next_event : t;
            for (int i = 0; i < nx; i++) x[i] = x[i] + (t1 - t) * dx[i];
            CHECK(set_time(m, t1));
            t = t1;
            CHECK(set_states(m, x, (size_t)nx));
            fmi2Boolean enter_event = 0, terminate_simulation = 0;
            CHECK(completed(m, 0, &enter_event, &terminate_simulation));
            if (terminate_simulation) { fprintf(stderr, "terminateSimulation at t = %g\n", t); return 1; }
            CHECK(get_indicators(m, z1, (size_t)ni));
            int state_event = 0;
            for (int i = 0; i < ni; i++) state_event |= (z1[i] > 0) != (z[i] > 0);
            memcpy(z, z1, (size_t)ni * sizeof(double));
            if (time_event || state_event || enter_event) {
                CHECK(enter_event_mode(m));
                if (event_iteration(new_discrete_states, m, &info)) return 1;
                CHECK(enter_ct_mode(m));
                time_events = info.nextEventTimeDefined;
                next_event = info.nextEventTime;
                CHECK(get_indicators(m, z, (size_t)ni));
            }
        }
        CHECK(get_real(m, vrs, nvr, me_values));
        CHECK(terminate(m));
        free_instance(m);
        free(x);
        free(dx);
        free(z);
        free(z1);
    }
    if (dlclose(lib)) { fprintf(stderr, "dlclose: %s\n", dlerror()); return 1; }

    printf("final");
    for (size_t i = 0; i < nvr; i++) {
        uint64_t b;
        memcpy(&b, &values[i], sizeof b);
        printf(" %llx", (unsigned long long)b);
    }
    printf("\nmessages %d\n", messages);
    if (getenv("HOST_TRACE")) {
        for (int n = 0; n < steps; n++) {
            printf("trace %d", n);
            for (size_t i = 0; i < nvr; i++) {
                uint64_t b;
                memcpy(&b, &trace[(size_t)n * nvr + i], sizeof b);
                printf(" %llx", (unsigned long long)b);
            }
            printf("\n");
        }
    }
    if (me_values) {
        printf("me-final");
        for (size_t i = 0; i < nvr; i++) {
            uint64_t b;
            memcpy(&b, &me_values[i], sizeof b);
            printf(" %llx", (unsigned long long)b);
        }
        printf("\n");
        free(me_values);
    }
    free(values);
    free(trace);
    return 0;
}

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
 * of this exporter's conventions are left out. */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

    for (int run = 0; run < 2; run++) {
        for (int i = 7; i < argc; i++) {
            fmi2ValueReference vr = (fmi2ValueReference)atoi(argv[i]);
            double v = atof(strchr(argv[i], '=') + 1);
            CHECK(set_real(c, &vr, 1, &v));
        }
        CHECK(setup(c, 0, 0.0, 0.0, 0, 0.0));
        CHECK(enter(c));
        CHECK(exit_init(c));
        if (do_step(c, 0.0, -1.0, 1) != fmi2Error) { fprintf(stderr, "h < 0 accepted\n"); return 1; }
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
    if (dlclose(lib)) { fprintf(stderr, "dlclose: %s\n", dlerror()); return 1; }

    printf("final");
    for (size_t i = 0; i < nvr; i++) {
        uint64_t b;
        memcpy(&b, &values[i], sizeof b);
        printf(" %llx", (unsigned long long)b);
    }
    printf("\nmessages %d\n", messages);
    free(values);
    free(trace);
    return 0;
}

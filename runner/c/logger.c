/* The importer's fmi2CallbackLogger of rustfmu-runner (runner/src/fmi2.rs).
 *
 * FMI declares the logger variadic (message is a printf format with its arguments), and stable
 * Rust cannot define a variadic function. This one formats the message with vsnprintf, as the
 * standard says, and hands the text to the Rust function whose address is the first field of
 * the componentEnvironment (runner/src/fmi2.rs: LogEnv). Being C in a static library, it is not
 * exported from a library the runner is linked into (rustc's version script exports Rust's
 * symbols only). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

typedef void (*rustfmu_sink)(void *env, const char *instance, unsigned int status, const char *category,
                             const char *text);

void rustfmu_runner_logger(void *env, const char *instance, unsigned int status, const char *category,
                           const char *message, ...) {
    if (env == NULL) return;
    rustfmu_sink sink = *(rustfmu_sink *)env;
    if (sink == NULL) return;
    if (message == NULL) {
        sink(env, instance, status, category, "");
        return;
    }
    char small[1024];
    va_list args;
    va_start(args, message);
    int n = vsnprintf(small, sizeof small, message, args);
    va_end(args);
    if (n < 0) {
        sink(env, instance, status, category, message);
        return;
    }
    if ((size_t)n < sizeof small) {
        sink(env, instance, status, category, small);
        return;
    }
    char *big = (char *)malloc((size_t)n + 1);
    if (big == NULL) {
        sink(env, instance, status, category, small);
        return;
    }
    va_start(args, message);
    vsnprintf(big, (size_t)n + 1, message, args);
    va_end(args);
    sink(env, instance, status, category, big);
    free(big);
}

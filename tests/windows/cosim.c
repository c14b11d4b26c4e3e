/* A co-simulation importer of HaselPlatform and HaselPlatformReduced (the same inputs and
 * outputs, the same value references) in plain C, for FMI 2.0 and FMI 3.0, built twice
 * from this one file: with mingw-w64 for Windows (the FMU's DLL, run under Wine by
 * tests/python/test_windows.py) and with gcc for Linux (the FMU's .so), so that the two runs can
 * be compared line by line.
 *
 *   cosim 2 LIBRARY GUID RESOURCE_URI        (FMI 2.0: fmuResourceLocation is a file: URI)
 *   cosim 3 LIBRARY TOKEN RESOURCE_PATH      (FMI 3.0: resourcePath is a native path)
 *
 * It first calls the library wrongly (NULL pointers, calls in the wrong state, a wrong token,
 * bytes that are no FMU state) and checks that each returns an error, logged, rather than
 * crashing; then it runs 2 s of the paper's excitation U_i = 60 sin(3 pi t + (i-1) 2 pi/3) V at
 * 1 ms steps, takes the FMU state at 1 s, serializes it, and replays the second second twice
 * (from the state and from its deserialized bytes), which must repeat the first pass bit for
 * bit. Printed, one line per step: "y" then the time and the six outputs h1 h2 h3 tip_x tip_y
 * tip_z as the hexadecimal bits of each double, then "ok" lines and a closing "passed" line.
 * Any failure prints "FAIL ..." and exits with status 1.
 *
 * No misuse here is a caught panic, because no input of the C API makes the library panic: every
 * entry point runs the model inside catch_unwind (src/fmi_common/calls.rs, src/fmi2/exports.rs,
 * src/fmi3/exports.rs), what can still panic behind it are invariants of the code (an expect
 * naming why it holds), not arguments, and the sequence fuzzers of ci/fuzz.sh, whose panic hook
 * aborts on any panic, caught or not, found none (book/src/tests.md, "Fuzzing"). The catching is
 * tested with
 * a test core that panics on request (src/fmi2/tests/lifecycle.rs, the same code for FMI 3.0); it
 * is the same on Windows, where the release profile's panic = "unwind" keeps it working.
 *
 * The few FMI types and prototypes used are declared here as the standards' headers define them
 * (fmi2FunctionTypes.h, fmi3FunctionTypes.h).
 */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
/* after windows.h, which it needs */
#include <shellapi.h>
typedef HMODULE Library;
/* FMI strings are UTF-8 (the resource path included), so the arguments are taken as UTF-8 from
 * the wide command line, not in the ANSI code page of main's argv, and paths are opened wide. */
static char **utf8_arguments(int *argc) {
    wchar_t **wide = CommandLineToArgvW(GetCommandLineW(), argc);
    char **out = calloc((size_t)*argc + 1, sizeof(char *));
    for (int i = 0; i < *argc; i++) {
        int n = WideCharToMultiByte(CP_UTF8, 0, wide[i], -1, NULL, 0, NULL, NULL);
        out[i] = malloc((size_t)n);
        WideCharToMultiByte(CP_UTF8, 0, wide[i], -1, out[i], n, NULL, NULL);
    }
    LocalFree(wide);
    return out;
}
static Library open_library(const char *path) {
    wchar_t wide[4096];
    if (!MultiByteToWideChar(CP_UTF8, 0, path, -1, wide, 4096)) return NULL;
    return LoadLibraryW(wide);
}
static void *symbol(Library lib, const char *name) { return (void *)GetProcAddress(lib, name); }
static void close_library(Library lib) { FreeLibrary(lib); }
#else
#include <dlfcn.h>
typedef void *Library;
static char **utf8_arguments(int *argc) {
    (void)argc;
    return NULL;
}
static Library open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(Library lib, const char *name) { return dlsym(lib, name); }
static void close_library(Library lib) { dlclose(lib); }
#endif

enum { FMI_OK = 0, FMI_ERROR = 3 };
enum { STEPS = 2000, HALF = 1000, NY = 6 };
static const double H = 1e-3;
static const unsigned int U_VR[3] = {0, 1, 2};
static const unsigned int Y_VR[NY] = {3, 4, 5, 6, 7, 8};

static int failures = 0;
static int errors_logged = 0;

#define CHECK(cond, ...)                                                                          \
    do {                                                                                          \
        if (!(cond)) {                                                                            \
            printf("FAIL line %d: ", __LINE__);                                                   \
            printf(__VA_ARGS__);                                                                  \
            printf("\n");                                                                         \
            failures++;                                                                           \
        }                                                                                         \
    } while (0)

/* A misuse call must return an error status and log why (at least one logged error). */
#define MISUSE(call, what)                                                                        \
    do {                                                                                          \
        int logged_before = errors_logged;                                                        \
        int status = (call);                                                                      \
        CHECK(status == FMI_ERROR, "%s returned %d, not an error", what, status);                    \
        CHECK(errors_logged > logged_before, "%s logged no error", what);                         \
        if (status == FMI_ERROR && errors_logged > logged_before) printf("ok misuse: %s\n", what);    \
    } while (0)

static void *need(Library lib, const char *name) {
    void *f = symbol(lib, name);
    if (!f) {
        printf("FAIL: the library does not export %s\n", name);
        exit(1);
    }
    return f;
}

static double excitation(int i, double t) {
    const double pi = 3.14159265358979323846;
    return 60.0 * sin(3.0 * pi * t + i * 2.0 * pi / 3.0);
}

static void print_outputs(double t, const double *y) {
    uint64_t bits;
    memcpy(&bits, &t, 8);
    printf("y %016llx", (unsigned long long)bits);
    for (int k = 0; k < NY; k++) {
        memcpy(&bits, &y[k], 8);
        printf(" %016llx", (unsigned long long)bits);
    }
    printf("\n");
}

/* What the run needs of either version: one instance, set up and initialized at t = 0. */
typedef struct {
    void *c;
    int (*set_inputs)(void *self, const double *u);
    int (*get_outputs)(void *self, double *y);
    int (*step)(void *self, double t, double h);
    int (*get_state)(void *self, void **state);
    int (*set_state)(void *self, void *state);
    int (*free_state)(void *self, void **state);
    int (*serialize)(void *self, void *state, char **bytes, size_t *size);
    int (*deserialize)(void *self, const char *bytes, size_t size, void **state);
} Run;

/* ---- FMI 2.0 ---------------------------------------------------------------------------- */

typedef void (*fmi2Logger)(void *env, const char *name, int status, const char *category,
                           const char *message, ...);
typedef struct {
    fmi2Logger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, int);
    void *componentEnvironment;
} fmi2CallbackFunctions;

static struct {
    void *(*Instantiate)(const char *, int, const char *, const char *,
                         const fmi2CallbackFunctions *, int, int);
    void (*FreeInstance)(void *);
    int (*SetupExperiment)(void *, int, double, double, int, double);
    int (*EnterInitializationMode)(void *);
    int (*ExitInitializationMode)(void *);
    int (*Terminate)(void *);
    int (*GetReal)(void *, const unsigned int *, size_t, double *);
    int (*SetReal)(void *, const unsigned int *, size_t, const double *);
    int (*DoStep)(void *, double, double, int);
    int (*GetFMUstate)(void *, void **);
    int (*SetFMUstate)(void *, void *);
    int (*FreeFMUstate)(void *, void **);
    int (*SerializedFMUstateSize)(void *, void *, size_t *);
    int (*SerializeFMUstate)(void *, void *, char *, size_t);
    int (*DeSerializeFMUstate)(void *, const char *, size_t, void **);
} f2;

static void logger2(void *env, const char *name, int status, const char *category,
                    const char *message, ...) {
    (void)env;
    char text[1024];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof text, message, args);
    va_end(args);
    if (status >= FMI_ERROR) errors_logged++;
    printf("log %s %d %s: %s\n", name ? name : "(null)", status, category ? category : "(null)",
           text);
}

static const fmi2CallbackFunctions callbacks2 = {logger2, calloc, free, NULL, NULL};

static int set_inputs2(void *c, const double *u) { return f2.SetReal(c, U_VR, 3, u); }
static int get_outputs2(void *c, double *y) { return f2.GetReal(c, Y_VR, NY, y); }
static int step2(void *c, double t, double h) { return f2.DoStep(c, t, h, 1); }
static int get_state2(void *c, void **s) { return f2.GetFMUstate(c, s); }
static int set_state2(void *c, void *s) { return f2.SetFMUstate(c, s); }
static int free_state2(void *c, void **s) { return f2.FreeFMUstate(c, s); }
static int serialize2(void *c, void *s, char **bytes, size_t *size) {
    int st = f2.SerializedFMUstateSize(c, s, size);
    if (st != FMI_OK) return st;
    *bytes = malloc(*size);
    return f2.SerializeFMUstate(c, s, *bytes, *size);
}
static int deserialize2(void *c, const char *bytes, size_t size, void **s) {
    return f2.DeSerializeFMUstate(c, bytes, size, s);
}

static void *instantiate2(const char *guid, const char *uri) {
    void *c = f2.Instantiate("cosim", 1, guid, uri, &callbacks2, 0, 0);
    if (!c) return NULL;
    if (f2.SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) != FMI_OK) return NULL;
    return c;
}

static Run load2(Library lib, const char *guid, const char *uri) {
#define LOAD(name) *(void **)&f2.name = need(lib, "fmi2" #name)
    LOAD(Instantiate); LOAD(FreeInstance); LOAD(SetupExperiment);
    LOAD(EnterInitializationMode); LOAD(ExitInitializationMode); LOAD(Terminate);
    LOAD(GetReal); LOAD(SetReal); LOAD(DoStep); LOAD(GetFMUstate); LOAD(SetFMUstate);
    LOAD(FreeFMUstate); LOAD(SerializedFMUstateSize); LOAD(SerializeFMUstate);
    LOAD(DeSerializeFMUstate);
#undef LOAD
    /* misuse: no instance without callbacks or with another GUID, NULL instance and pointers,
     * calls before initialization, a NULL state and bytes that are no state */
    CHECK(!f2.Instantiate("x", 1, guid, uri, NULL, 0, 0), "instantiated without callbacks");
    int before = errors_logged;
    CHECK(!f2.Instantiate("x", 1, "{00000000-0000-0000-0000-000000000000}", uri, &callbacks2,
                          0, 0), "instantiated with a wrong GUID");
    CHECK(errors_logged > before, "the wrong GUID logged no error");
    CHECK(f2.DoStep(NULL, 0.0, H, 1) == FMI_ERROR, "fmi2DoStep(NULL) is no error");
    void *m = instantiate2(guid, uri);
    CHECK(m != NULL, "no instance for the misuse checks");
    if (m) {
        double y[NY];
        void *state = NULL;
        MISUSE(f2.DoStep(m, 0.0, H, 1), "fmi2DoStep before initialization");
        CHECK(f2.EnterInitializationMode(m) == FMI_OK && f2.ExitInitializationMode(m) == FMI_OK,
              "the instance no longer initializes after the misuse");
        MISUSE(f2.GetReal(m, Y_VR, NY, NULL), "fmi2GetReal into NULL");
        MISUSE(f2.GetReal(m, NULL, NY, y), "fmi2GetReal of NULL value references");
        MISUSE(f2.SetFMUstate(m, NULL), "fmi2SetFMUstate(NULL)");
        MISUSE(f2.DeSerializeFMUstate(m, "no FMU state at all, just text", 30, &state),
               "fmi2DeSerializeFMUstate of bytes that are no state");
        CHECK(state == NULL, "a state was made of bad bytes");
        MISUSE(f2.DoStep(m, 0.5, H, 1), "fmi2DoStep at the wrong time");
        CHECK(f2.DoStep(m, 0.0, H, 1) == FMI_OK, "the instance no longer steps after the misuse");
        CHECK(f2.Terminate(m) == FMI_OK, "fmi2Terminate");
        MISUSE(f2.DoStep(m, H, H, 1), "fmi2DoStep after fmi2Terminate");
        f2.FreeInstance(m);
    }
    f2.FreeInstance(NULL);
    Run r = {NULL, set_inputs2, get_outputs2, step2, get_state2,
             set_state2, free_state2, serialize2, deserialize2};
    r.c = instantiate2(guid, uri);
    CHECK(r.c != NULL, "no instance");
    if (r.c) {
        CHECK(f2.EnterInitializationMode(r.c) == FMI_OK, "fmi2EnterInitializationMode");
        CHECK(f2.ExitInitializationMode(r.c) == FMI_OK, "fmi2ExitInitializationMode");
    }
    return r;
}

/* ---- FMI 3.0 ---------------------------------------------------------------------------- */

typedef void (*fmi3LogMessage)(void *env, int status, const char *category, const char *message);

static struct {
    void *(*InstantiateCoSimulation)(const char *, const char *, const char *, bool, bool, bool,
                                     bool, const unsigned int *, size_t, void *, fmi3LogMessage,
                                     void *);
    void (*FreeInstance)(void *);
    int (*EnterInitializationMode)(void *, bool, double, double, bool, double);
    int (*ExitInitializationMode)(void *);
    int (*Terminate)(void *);
    int (*GetFloat64)(void *, const unsigned int *, size_t, double *, size_t);
    int (*SetFloat64)(void *, const unsigned int *, size_t, const double *, size_t);
    int (*DoStep)(void *, double, double, bool, bool *, bool *, bool *, double *);
    int (*GetFMUState)(void *, void **);
    int (*SetFMUState)(void *, void *);
    int (*FreeFMUState)(void *, void **);
    int (*SerializedFMUStateSize)(void *, void *, size_t *);
    int (*SerializeFMUState)(void *, void *, uint8_t *, size_t);
    int (*DeserializeFMUState)(void *, const uint8_t *, size_t, void **);
} f3;

static void logger3(void *env, int status, const char *category, const char *message) {
    (void)env;
    if (status >= FMI_ERROR) errors_logged++;
    printf("log %d %s: %s\n", status, category ? category : "(null)",
           message ? message : "(null)");
}

static int set_inputs3(void *c, const double *u) { return f3.SetFloat64(c, U_VR, 3, u, 3); }
static int get_outputs3(void *c, double *y) { return f3.GetFloat64(c, Y_VR, NY, y, NY); }
static int step3(void *c, double t, double h) {
    bool event, terminate, early;
    double last;
    return f3.DoStep(c, t, h, false, &event, &terminate, &early, &last);
}
static int get_state3(void *c, void **s) { return f3.GetFMUState(c, s); }
static int set_state3(void *c, void *s) { return f3.SetFMUState(c, s); }
static int free_state3(void *c, void **s) { return f3.FreeFMUState(c, s); }
static int serialize3(void *c, void *s, char **bytes, size_t *size) {
    int st = f3.SerializedFMUStateSize(c, s, size);
    if (st != FMI_OK) return st;
    *bytes = malloc(*size);
    return f3.SerializeFMUState(c, s, (uint8_t *)*bytes, *size);
}
static int deserialize3(void *c, const char *bytes, size_t size, void **s) {
    return f3.DeserializeFMUState(c, (const uint8_t *)bytes, size, s);
}

static void *instantiate3(const char *token, const char *resources) {
    return f3.InstantiateCoSimulation("cosim", token, resources, false, false, false, false, NULL,
                                      0, NULL, logger3, NULL);
}

static Run load3(Library lib, const char *token, const char *resources) {
#define LOAD(name) *(void **)&f3.name = need(lib, "fmi3" #name)
    LOAD(InstantiateCoSimulation); LOAD(FreeInstance); LOAD(EnterInitializationMode);
    LOAD(ExitInitializationMode); LOAD(Terminate); LOAD(GetFloat64); LOAD(SetFloat64);
    LOAD(DoStep); LOAD(GetFMUState); LOAD(SetFMUState); LOAD(FreeFMUState);
    LOAD(SerializedFMUStateSize); LOAD(SerializeFMUState); LOAD(DeserializeFMUState);
#undef LOAD
    int before = errors_logged;
    CHECK(!f3.InstantiateCoSimulation("x", "{0}", resources, false, false, false, false, NULL, 0,
                                      NULL, logger3, NULL), "instantiated with a wrong token");
    CHECK(errors_logged > before, "the wrong token logged no error");
    bool flags[3];
    double last;
    CHECK(f3.DoStep(NULL, 0.0, H, false, &flags[0], &flags[1], &flags[2], &last) == FMI_ERROR,
          "fmi3DoStep(NULL) is no error");
    void *m = instantiate3(token, resources);
    CHECK(m != NULL, "no instance for the misuse checks");
    if (m) {
        double y[NY];
        void *state = NULL;
        MISUSE(step3(m, 0.0, H), "fmi3DoStep before initialization");
        CHECK(f3.EnterInitializationMode(m, false, 0.0, 0.0, false, 0.0) == FMI_OK &&
                  f3.ExitInitializationMode(m) == FMI_OK,
              "the instance no longer initializes after the misuse");
        MISUSE(f3.GetFloat64(m, Y_VR, NY, NULL, NY), "fmi3GetFloat64 into NULL");
        MISUSE(f3.GetFloat64(m, Y_VR, NY, y, 1), "fmi3GetFloat64 with nValues too small");
        MISUSE(f3.DoStep(m, 0.0, H, false, NULL, &flags[1], &flags[2], &last),
               "fmi3DoStep with eventHandlingNeeded NULL");
        MISUSE(f3.SetFMUState(m, NULL), "fmi3SetFMUState(NULL)");
        MISUSE(f3.DeserializeFMUState(m, (const uint8_t *)"no FMU state at all, just text", 30,
                                      &state),
               "fmi3DeserializeFMUState of bytes that are no state");
        CHECK(state == NULL, "a state was made of bad bytes");
        CHECK(step3(m, 0.0, H) == FMI_OK, "the instance no longer steps after the misuse");
        CHECK(f3.Terminate(m) == FMI_OK, "fmi3Terminate");
        MISUSE(step3(m, H, H), "fmi3DoStep after fmi3Terminate");
        f3.FreeInstance(m);
    }
    f3.FreeInstance(NULL);
    Run r = {NULL, set_inputs3, get_outputs3, step3, get_state3,
             set_state3, free_state3, serialize3, deserialize3};
    r.c = instantiate3(token, resources);
    CHECK(r.c != NULL, "no instance");
    if (r.c) {
        CHECK(f3.EnterInitializationMode(r.c, false, 0.0, 0.0, false, 0.0) == FMI_OK,
              "fmi3EnterInitializationMode");
        CHECK(f3.ExitInitializationMode(r.c) == FMI_OK, "fmi3ExitInitializationMode");
    }
    return r;
}

/* ---- the run ---------------------------------------------------------------------------- */

/* Steps from step `from` to `to`, the outputs after each step into y[step]. */
static void steps(Run *r, int from, int to, double (*y)[NY]) {
    for (int n = from; n < to; n++) {
        double t = n * H;
        double u[3] = {excitation(0, t), excitation(1, t), excitation(2, t)};
        CHECK(r->set_inputs(r->c, u) == FMI_OK, "setting the inputs at t = %g", t);
        CHECK(r->step(r->c, t, H) == FMI_OK, "the step at t = %g", t);
        CHECK(r->get_outputs(r->c, y[n]) == FMI_OK, "getting the outputs at t = %g", t);
    }
}

/* Whether the second half of `again` repeats that of `first` bit for bit. */
static int same_second_half(double (*first)[NY], double (*again)[NY]) {
    return !memcmp(first[HALF], again[HALF], sizeof(double) * NY * (STEPS - HALF));
}

int main(int argc, char **argv) {
    char **utf8 = utf8_arguments(&argc);
    if (utf8) argv = utf8;
    if (argc != 5 || (strcmp(argv[1], "2") && strcmp(argv[1], "3"))) {
        fprintf(stderr, "usage: cosim 2|3 LIBRARY GUID|TOKEN RESOURCE_URI|RESOURCE_PATH\n");
        return 2;
    }
    setvbuf(stdout, NULL, _IOFBF, 1 << 16);
    Library lib = open_library(argv[2]);
    if (!lib) {
        printf("FAIL: cannot load %s\n", argv[2]);
        return 1;
    }
    int fmi3 = argv[1][0] == '3';
    Run r = fmi3 ? load3(lib, argv[3], argv[4]) : load2(lib, argv[3], argv[4]);
    if (!r.c) return 1;
    int errors_before = errors_logged;
    static double first[STEPS][NY], again[STEPS][NY];
    void *state = NULL, *restored = NULL;
    char *bytes = NULL;
    size_t size = 0;
    steps(&r, 0, HALF, first);
    CHECK(r.get_state(r.c, &state) == FMI_OK && state, "getting the FMU state");
    CHECK(r.serialize(r.c, state, &bytes, &size) == FMI_OK && size > 0, "serializing the FMU state");
    steps(&r, HALF, STEPS, first);
    CHECK(r.set_state(r.c, state) == FMI_OK, "setting the FMU state");
    steps(&r, HALF, STEPS, again);
    CHECK(same_second_half(first, again), "the replay from the FMU state differs");
    CHECK(r.deserialize(r.c, bytes, size, &restored) == FMI_OK && restored,
          "deserializing the FMU state");
    memset(again, 0, sizeof again);
    CHECK(r.set_state(r.c, restored) == FMI_OK, "setting the deserialized FMU state");
    steps(&r, HALF, STEPS, again);
    CHECK(same_second_half(first, again), "the replay from the serialized FMU state differs");
    if (!failures) printf("ok replay: from the FMU state and from its %d bytes, bit for bit\n", (int)size);
    CHECK(r.free_state(r.c, &state) == FMI_OK && !state, "freeing the FMU state");
    CHECK(r.free_state(r.c, &restored) == FMI_OK && !restored, "freeing the deserialized state");
    free(bytes);
    CHECK(errors_logged == errors_before, "the run logged %d errors", errors_logged - errors_before);
    if (fmi3) {
        CHECK(f3.Terminate(r.c) == FMI_OK, "fmi3Terminate");
        f3.FreeInstance(r.c);
    } else {
        CHECK(f2.Terminate(r.c) == FMI_OK, "fmi2Terminate");
        f2.FreeInstance(r.c);
    }
    for (int n = 0; n < STEPS; n++) print_outputs((n + 1) * H, first[n]);
    close_library(lib);
    printf(failures ? "FAIL: %d checks failed\n" : "all checks passed\n", failures);
    return failures ? 1 : 0;
}

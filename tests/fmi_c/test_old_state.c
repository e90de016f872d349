/* A serialised FMU state of an earlier format version, written by the FMU before the format of
 * fmu_src/core/fmu_state.h (version 4): the oscillator's version 3 and the chain's version 1, kept
 * as fixtures (tests/fmi_c/fixtures/, hex, produced by the FMUs of that time). Deserialising one
 * is refused with fmi2Error and one sentence naming the version found and the one expected; a
 * state of the current format still round-trips in the same instance.
 *
 * Usage: test_old_state FIXTURE.hex VERSION_FOUND (linked against one FMI 2.0 FMU). */
#include "fmi2Functions.h"
#include "model_vars.h"
#include "../check.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char g_last[1024];

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    (void)env; (void)name; (void)category;
    if (status >= fmi2Error) snprintf(g_last, sizeof g_last, "%s", message);
}

static size_t read_hex(const char *path, unsigned char *buf, size_t cap)
{
    FILE *f = fopen(path, "r");
    if (!f) return 0;
    size_t n = 0;
    unsigned int byte;
    while (n < cap && fscanf(f, "%2x", &byte) == 1) buf[n++] = (unsigned char)byte;
    fclose(f);
    return n;
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: test_old_state FIXTURE.hex VERSION_FOUND\n");
        return 2;
    }
    static unsigned char old[1 << 16];
    const size_t n = read_hex(argv[1], old, sizeof old);
    checks t = {0, 0, NULL, {0}}, *T = &t;
    EXPECT(n > 24);
    const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("old", fmi2CoSimulation, MODEL_GUID, "", &cb, fmi2False, fmi2False);
    EXPECT(c != NULL);
    if (!c) return 1;
    fmi2FMUstate s = NULL;
    EXPECT(fmi2DeSerializeFMUstate(c, (const fmi2Byte *)old, n, &s) == fmi2Error && s == NULL);
    char expected[64];
    snprintf(expected, sizeof expected, "format version %s", argv[2]);
    printf("refused: %s\n", g_last);
    EXPECT(strstr(g_last, expected) != NULL);
    EXPECT(strstr(g_last, "reads format version 7") != NULL);
    /* the current format: serialise and deserialise a state of this instance */
    EXPECT(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK);
    EXPECT(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) <= fmi2Warning);
    EXPECT(fmi2GetFMUstate(c, &s) == fmi2OK);
    size_t size = 0;
    EXPECT(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK && size > 32);
    unsigned char *buf = (unsigned char *)malloc(size);
    fmi2FMUstate s2 = NULL;
    EXPECT(buf && fmi2SerializeFMUstate(c, s, (fmi2Byte *)buf, size) == fmi2OK);
    EXPECT(buf && memcmp(buf, "DFOSTATE\x07\0\0\0", 12) == 0);
    EXPECT(buf && fmi2DeSerializeFMUstate(c, (const fmi2Byte *)buf, size, &s2) == fmi2OK && s2 != NULL);
    EXPECT(fmi2SetFMUstate(c, s2) == fmi2OK);
    fmi2FreeFMUstate(c, &s);
    fmi2FreeFMUstate(c, &s2);
    free(buf);
    fmi2FreeInstance(c);
    return checks_done(T, "test_old_state");
}

/* A PD servo as an FMI 2.0 Co-Simulation FMU of its own, written against
   the official FMI 2.0 headers only: inputs `position` (m) and `velocity`
   (m/s), parameters `k` (N/m), `c` (N s/m) and `reference` (m), output
   `force` = -(k (position - reference) + c velocity), computed from the
   inputs held at the start of each communication step. Its gains start at
   zero: the system that holds it sets them (an SSP's parameter bindings).
   `make_loop.sh` beside it compiles it, packs it with its model description
   (pd_controller.xml) and lets `fistage ssp` put it in a system with the
   plant; the SSP test of ffi/tests/fmpy.rs does the same in Rust. */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

enum { VR_POSITION, VR_VELOCITY, VR_K, VR_C, VR_REFERENCE, VR_FORCE, N_VARIABLES };

typedef struct {
    fmi2Real value[N_VARIABLES];
    fmi2Real time;
} Controller;

static void update(Controller *s) {
    s->value[VR_FORCE] = -(s->value[VR_K] * (s->value[VR_POSITION] - s->value[VR_REFERENCE]) +
                           s->value[VR_C] * s->value[VR_VELOCITY]);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    (void)c; (void)on; (void)n; (void)cats;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean logging) {
    (void)name; (void)guid; (void)resources; (void)functions; (void)visible; (void)logging;
    if (type != fmi2CoSimulation) return NULL;
    Controller *s = calloc(1, sizeof(Controller));
    if (s == NULL) return NULL;
    update(s);
    return s;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance,
                               fmi2Real start, fmi2Boolean stop_defined, fmi2Real stop) {
    (void)tolerance_defined; (void)tolerance; (void)stop_defined; (void)stop;
    ((Controller *)c)->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { update(c); return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) { (void)c; return fmi2Error; }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    Controller *s = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= N_VARIABLES) return fmi2Error;
        v[i] = s->value[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    Controller *s = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= N_VARIABLES || vr[i] == VR_FORCE) return fmi2Error;
        s->value[vr[i]] = v[i];
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real point, fmi2Real step, fmi2Boolean no_rollback) {
    (void)no_rollback;
    Controller *s = c;
    update(s);
    s->time = point + step;
    return fmi2OK;
}

/* Everything else this controller does not do. */
#define REFUSE(name, ...) fmi2Status name(__VA_ARGS__) { return fmi2Error; }
REFUSE(fmi2GetInteger, fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[])
REFUSE(fmi2GetBoolean, fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[])
REFUSE(fmi2GetString, fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[])
REFUSE(fmi2SetInteger, fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[])
REFUSE(fmi2SetBoolean, fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[])
REFUSE(fmi2SetString, fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[])
REFUSE(fmi2GetFMUstate, fmi2Component c, fmi2FMUstate *state)
REFUSE(fmi2SetFMUstate, fmi2Component c, fmi2FMUstate state)
REFUSE(fmi2FreeFMUstate, fmi2Component c, fmi2FMUstate *state)
REFUSE(fmi2SerializedFMUstateSize, fmi2Component c, fmi2FMUstate state, size_t *size)
REFUSE(fmi2SerializeFMUstate, fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size)
REFUSE(fmi2DeSerializeFMUstate, fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state)
REFUSE(fmi2GetDirectionalDerivative, fmi2Component c, const fmi2ValueReference u[], size_t nu,
       const fmi2ValueReference z[], size_t nz, const fmi2Real dz[], fmi2Real du[])
REFUSE(fmi2SetRealInputDerivatives, fmi2Component c, const fmi2ValueReference vr[], size_t n,
       const fmi2Integer order[], const fmi2Real v[])
REFUSE(fmi2GetRealOutputDerivatives, fmi2Component c, const fmi2ValueReference vr[], size_t n,
       const fmi2Integer order[], fmi2Real v[])
REFUSE(fmi2CancelStep, fmi2Component c)
REFUSE(fmi2GetStatus, fmi2Component c, const fmi2StatusKind s, fmi2Status *v)
REFUSE(fmi2GetRealStatus, fmi2Component c, const fmi2StatusKind s, fmi2Real *v)
REFUSE(fmi2GetIntegerStatus, fmi2Component c, const fmi2StatusKind s, fmi2Integer *v)
REFUSE(fmi2GetBooleanStatus, fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v)
REFUSE(fmi2GetStringStatus, fmi2Component c, const fmi2StatusKind s, fmi2String *v)

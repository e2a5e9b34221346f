/* A minimal FMI 2.0 co-simulation frame around one model of real variables.
 *
 * The model (a .c file next to this one) provides model.h's three functions; the variable
 * table (value references, start values, MODEL_IDENTIFIER, MODEL_GUID) is generated into
 * model_vars.h by ego.fmi.build from the same table that writes modelDescription.xml, so the
 * two cannot disagree. Every real variable lives in one array indexed by its value reference.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model_vars.h"
#include "model.h"
#include "fmi2Functions.h"

typedef enum { ST_INSTANTIATED, ST_INIT, ST_STEP, ST_TERMINATED, ST_ERROR } State;

typedef struct {
    ModelData m;
    State state;
    fmi2CallbackFunctions cb;
    fmi2String name;
    fmi2Boolean logging;
    double time;
} Instance;

static void frame_log(void *env, int status, const char *category, const char *message)
{
    Instance *inst = (Instance *)env;
    if (inst->cb.logger && (inst->logging || status >= MODEL_WARNING))
        /* the message is the format (no arguments): the models' messages hold no '%' */
        inst->cb.logger(inst->cb.componentEnvironment, inst->name, (fmi2Status)status, category, message);
}

static void set_start(Instance *inst)
{
    memcpy(inst->m.r, MODEL_START, sizeof(MODEL_START));
    inst->m.steps = 0;
    inst->m.log = frame_log;
    inst->m.env = inst;
    inst->time = 0.0;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[])
{
    (void)n; (void)cats;
    ((Instance *)c)->logging = on;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging)
{
    (void)location; (void)visible;
    if (type != fmi2CoSimulation || !guid || strcmp(guid, MODEL_GUID) != 0) {
        if (cb && cb->logger)
            cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                       "wrong FMU type or GUID (expected co-simulation and " MODEL_GUID ")");
        return NULL;
    }
#ifdef MODEL_ON_INSTANTIATE
    MODEL_ON_INSTANTIATE; /* a test model's hook (tests/fmi/c/misbehave.c) */
#endif
    Instance *inst = (Instance *)calloc(1, sizeof(Instance));
    if (!inst) return NULL;
    if (cb) inst->cb = *cb;
    inst->name = name;
    inst->logging = logging;
    set_start(inst);
    inst->state = ST_INSTANTIATED;
    return inst;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDef, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stopDef, fmi2Real stop)
{
    (void)tolDef; (void)tol; (void)stopDef; (void)stop;
    ((Instance *)c)->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { ((Instance *)c)->state = ST_INIT; return fmi2OK; }

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance *inst = (Instance *)c;
    int status = model_init(&inst->m);
    inst->state = status >= MODEL_ERROR ? ST_ERROR : ST_STEP;
    return (fmi2Status)status;
}

fmi2Status fmi2Terminate(fmi2Component c) { ((Instance *)c)->state = ST_TERMINATED; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component c)
{
    Instance *inst = (Instance *)c;
    set_start(inst);
    inst->state = ST_INSTANTIATED;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    Instance *inst = (Instance *)c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= MODEL_N_REALS) return fmi2Error;
        value[i] = inst->m.r[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    Instance *inst = (Instance *)c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= MODEL_N_REALS) return fmi2Error;
        inst->m.r[vr[i]] = value[i];
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior)
{
    (void)noSetPrior;
    Instance *inst = (Instance *)c;
    if (inst->state != ST_STEP) {
        frame_log(inst, MODEL_ERROR, "logStatusError", "fmi2DoStep outside step mode");
        return fmi2Error;
    }
    int status = model_step(&inst->m, t, h);
    inst->m.steps++;
    inst->time = t + h;
    if (status >= MODEL_ERROR) inst->state = ST_ERROR;
    return (fmi2Status)status;
}

/* not supported by these models: integers, booleans, strings, states, derivatives */
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[])
{ (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n)
{ (void)c; (void)s; (void)n; return fmi2Error; }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
{ (void)c; (void)s; (void)b; (void)n; return fmi2Error; }
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
{ (void)c; (void)b; (void)n; (void)s; return fmi2Error; }
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real dv[], fmi2Real dz[])
{ (void)c; (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz; return fmi2Error; }
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[])
{ (void)c; (void)vr; (void)n; (void)order; (void)value; return fmi2Error; }
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[])
{ (void)c; (void)vr; (void)n; (void)order; (void)value; return fmi2Error; }
fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status *v)
{ (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real *v)
{
    if (k == fmi2LastSuccessfulTime) { *v = ((Instance *)c)->time; return fmi2OK; }
    return fmi2Discard;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer *v)
{ (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v)
{ (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *v)
{ (void)c; (void)k; (void)v; return fmi2Discard; }

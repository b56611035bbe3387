/* Every function of the generated header assigned to its official
   fmi2XxxTYPE pointer type: any mismatch in a parameter or return type is a
   diagnostic, and the test compiles with -Werror. */
#include "fistage_stage.h"

#define CHECK(name) name##TYPE *check_##name = name;

CHECK(fmi2GetTypesPlatform)
CHECK(fmi2GetVersion)
CHECK(fmi2SetDebugLogging)
CHECK(fmi2Instantiate)
CHECK(fmi2FreeInstance)
CHECK(fmi2SetupExperiment)
CHECK(fmi2EnterInitializationMode)
CHECK(fmi2ExitInitializationMode)
CHECK(fmi2Terminate)
CHECK(fmi2Reset)
CHECK(fmi2GetReal)
CHECK(fmi2GetInteger)
CHECK(fmi2GetBoolean)
CHECK(fmi2GetString)
CHECK(fmi2SetReal)
CHECK(fmi2SetInteger)
CHECK(fmi2SetBoolean)
CHECK(fmi2SetString)
CHECK(fmi2GetFMUstate)
CHECK(fmi2SetFMUstate)
CHECK(fmi2FreeFMUstate)
CHECK(fmi2SerializedFMUstateSize)
CHECK(fmi2SerializeFMUstate)
CHECK(fmi2DeSerializeFMUstate)
CHECK(fmi2GetDirectionalDerivative)
CHECK(fmi2SetRealInputDerivatives)
CHECK(fmi2GetRealOutputDerivatives)
CHECK(fmi2DoStep)
CHECK(fmi2CancelStep)
CHECK(fmi2GetStatus)
CHECK(fmi2GetRealStatus)
CHECK(fmi2GetIntegerStatus)
CHECK(fmi2GetBooleanStatus)
CHECK(fmi2GetStringStatus)
CHECK(fmi2EnterEventMode)
CHECK(fmi2NewDiscreteStates)
CHECK(fmi2EnterContinuousTimeMode)
CHECK(fmi2CompletedIntegratorStep)
CHECK(fmi2SetTime)
CHECK(fmi2SetContinuousStates)
CHECK(fmi2GetDerivatives)
CHECK(fmi2GetEventIndicators)
CHECK(fmi2GetContinuousStates)
CHECK(fmi2GetNominalsOfContinuousStates)

int main(void) {
    /* Linked against the library: the version string comes from it. */
    const char *version = check_fmi2GetVersion();
    return (version[0] == '2' && version[1] == '.' && version[2] == '0' && version[3] == 0) ? 0 : 1;
}

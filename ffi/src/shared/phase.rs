//! The FMI 2.0 state machines' phases (Co-Simulation and Model Exchange),
//! and their one-byte code in serialized FMU states.

/// Where an instance is in its FMI 2.0 state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// After fmi2Instantiate or fmi2Reset: parameters and inputs may be set.
    Instantiated,
    /// Between fmi2EnterInitializationMode and fmi2ExitInitializationMode.
    Initialization,
    /// Ready for fmi2DoStep.
    StepComplete,
    /// The last fmi2DoStep failed; the state may be restored or the instance reset.
    StepFailed,
    /// After fmi2Terminate: results may be read.
    Terminated,
    /// An internal error made the instance unusable; only fmi2FreeInstance helps.
    Fatal,
    /// Model Exchange: at an event (after initialisation or fmi2EnterEventMode).
    EventMode,
    /// Model Exchange: the importer integrates the continuous states.
    ContinuousTime,
}

impl Phase {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Phase::Instantiated => "instantiated",
            Phase::Initialization => "initialization mode",
            Phase::StepComplete => "step complete",
            Phase::StepFailed => "step failed",
            Phase::Terminated => "terminated",
            Phase::Fatal => "fatal error",
            Phase::EventMode => "event mode",
            Phase::ContinuousTime => "continuous-time mode",
        }
    }

    pub(crate) fn code(self) -> u8 {
        self as u8
    }

    pub(crate) fn from_code(code: u8) -> Option<Self> {
        [
            Phase::Instantiated,
            Phase::Initialization,
            Phase::StepComplete,
            Phase::StepFailed,
            Phase::Terminated,
            Phase::Fatal,
            Phase::EventMode,
            Phase::ContinuousTime,
        ]
        .into_iter()
        .find(|p| p.code() == code)
    }
}

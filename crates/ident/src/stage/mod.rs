//! Grey-box identification of any stage from its records: the quantities of
//! a scenario's assembled model (any robot file) named by their paths in the
//! parameter table, fitted by output error to the readings of its sensors.
//!
//! * [`plant`]: the stage with free parameters, simulated with exact
//!   state sensitivities (dual numbers) and central differences in the
//!   parameters;
//! * [`fit`]: the growing-horizon fit of one or more records, ties, and the
//!   jackknife intervals;
//! * [`identifiability`]: what the records determine, before and after;
//! * [`report`]: `fit.json` and `override.toml`.
//!
//! Records are those of [`crate::record`]: the force held over each sample
//! interval, the position column read by the stage's main sensor (the
//! servo's, else the first), and further columns named after sensors
//! (`bearing_encoder_nm`).
//!
//! ```no_run
//! use fistage_ident::stage::{Loop, StageOptions, StagePlant, fit_stage};
//! use fistage_ident::record::read_record;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let scenario = fistage_model::Scenario::from_file("scenarios/paper/fig05b_fi.toml".as_ref())?;
//! let robot = fistage_model::RobotSpec::from_file(&scenario.robot)?;
//! let paths = ["overrides.isolator.k_x".to_string(), "overrides.bearing_friction.f_c".into()];
//! let plant = StagePlant::new(&scenario, &robot, &paths, Loop::Open)?;
//! let record = read_record("record.csv", &Default::default())?;
//! let fit = fit_stage(&plant, &[record], &StageOptions::default(), &mut |_| true)?;
//! println!("{:?} undetermined: {:?}", fit.values, fit.undetermined());
//! # Ok(())
//! # }
//! ```

/// The nine physical parameters of the paper's FI stage
/// (`robots/stage_1dof_fi.urdf`: the isolator's stiffness and damping, the
/// bearing's mass and its six LuGre parameters) as parameter-table paths:
/// what a lab with that stage fits.
pub const PAPER_FI_PATHS: [&str; 9] = [
    "overrides.isolator.k_x",
    "overrides.isolator.c_x",
    "overrides.bearing.mass",
    "overrides.bearing_friction.f_c",
    "overrides.bearing_friction.f_s",
    "overrides.bearing_friction.v_s",
    "overrides.bearing_friction.sigma0",
    "overrides.bearing_friction.sigma1",
    "overrides.bearing_friction.sigma2",
];

pub mod fit;
pub mod identifiability;
pub mod plant;
pub mod report;

pub use fit::{Continuation, StageFit, StageOptions, StageProgress, fit_stage};
pub use identifiability::{DETERMINED_LOG_SD, Identifiability};
pub use plant::{Loop, StagePlant};
pub use report::{StageReport, stage_fit_csv};

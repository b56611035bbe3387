//! Identification from recorded stage runs: all six LuGre parameters (and
//! the mass) by output error on the encoder position.
//!
//! * [`data`]: the [`Record`] (time, force, position in SI units) and its
//!   conventions: the force is held over each sample interval, `force[k]`
//!   acting on `[t_k, t_k+1)`; `position[k]` is sampled at `t_k` before
//!   `force[k]` acts; the stage starts at rest with relaxed bristles unless
//!   a [`StartState`] is given;
//! * [`read`]: CSV and MAT-files, columns or variables by unit suffix
//!   (`t_s`, `f_servo_N`, `x_nm`);
//! * [`plant`]: paper Eq. 31 through fistage's engine, with exact forward
//!   sensitivities, driven by the recorded force or, for a closed-loop
//!   record, by a scenario's servo ([`servo_loop`]);
//! * [`segments`]: rests, chirps, ramps, holds and steps, from a table or
//!   found from the force;
//! * [`start`]: first estimates from the record itself;
//! * [`fit`]: the output-error fit and its block-jackknife intervals;
//! * [`report`]: `fit.json`, the table, `override.toml`;
//! * [`program`] and [`synth`]: lab-style records for tests and planning.
//!
//! ```
//! use fistage_ident::record::{RecordOptions, RecordSynth, fit_record};
//! use fistage_ident::synth::small_stage;
//!
//! let truth = small_stage();
//! let (record, _) = RecordSynth::new(truth, 0.25).generate().unwrap();
//! let fit = fit_record(&record, &RecordOptions::default(), &mut |_| true).unwrap();
//! assert!((fit.theta.lugre().f_c / truth.f_c - 1.0).abs() < 1e-3);
//! ```

pub mod data;
pub mod fit;
pub mod plant;
pub mod program;
pub mod read;
pub mod report;
pub mod segments;
pub mod servo_loop;
pub mod start;
pub mod synth;

pub use data::{Record, SensorColumn, StartState};
pub use fit::{
    FitProgress, JointUncertainty, MassChoice, RecordFit, RecordOptions, SegmentChoice, fit_record,
};
pub use plant::{RecordParam, Theta};
pub use read::{parse_record_mat, read_record};
pub use report::{RecordReport, record_fit_csv, record_override};
pub use segments::{Segment, detect_segments, read_segments};
pub use servo_loop::ServoLoop;
pub use synth::{LabErrors, RecordSynth};

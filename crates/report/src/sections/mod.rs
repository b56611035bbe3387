//! One file per kind of result: the section of the page that result makes.

pub mod compare;
pub mod identify;
pub mod modes;
pub mod robust;
pub mod run;
pub mod sweep;
pub mod tune;

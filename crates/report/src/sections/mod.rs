//! One file per kind of result: the section of the page that result makes.

pub mod modes;
pub mod run;

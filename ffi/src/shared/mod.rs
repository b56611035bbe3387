//! What the FMI 2.0 and FMI 3.0 faces share: the unit itself
//! ([`instance`], in safe Rust, with its [`variables`], its phase and its
//! serialized [`state`]), the registry of live instances every C call goes
//! through (`registry`), the C arguments as Rust values (`c_args`), the
//! call bodies both standards' functions run with their own names
//! (`calls`), the importer's logger and the statuses.

pub(crate) mod c_args;
pub(crate) mod calls;
pub mod instance;
pub(crate) mod logger;
pub(crate) mod phase;
pub(crate) mod registry;
pub(crate) mod resources;
pub(crate) mod state;
pub(crate) mod status;
pub mod variables;

//! One module per subcommand group.

pub mod cem;
pub mod design;
pub mod fe;
pub mod robot;
pub mod study;

//! The library's safe output writer ([`kappe::output`]), under the name the commands use.

pub use kappe::output::*;

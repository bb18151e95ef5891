//! One module per subcommand group.

pub mod buildability;
pub mod calibrate;
pub mod cem;
pub mod corrugation;
pub mod design;
pub mod designer;
pub mod fe;
pub mod init;
pub mod optimize;
pub mod robot;
pub mod schedule;
pub mod study;

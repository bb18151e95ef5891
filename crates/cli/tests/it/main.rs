//! The CLI's integration tests: one test binary (one link, one process start per
//! `cargo test`), a module per topic. Each module runs the `kappe` binary end to end.

mod ceiling;
mod collapse;
mod common;
mod corrugation;
mod design;
mod designer;
mod fe;
mod formats;
mod green;
mod operator;
mod reliability;
mod report;
mod robot;
mod schedule;
mod slurm;
mod study;
mod uncertainty;

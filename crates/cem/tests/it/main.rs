//! Integration tests of kappe-cem (one test binary, modules by topic).

mod common;
mod fixed_geometry;
mod fixtures;
mod indexed;
mod optimize;
mod properties;
mod validation;

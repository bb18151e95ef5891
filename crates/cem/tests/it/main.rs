//! Integration tests of kappe-cem (one test binary, modules by topic).

mod common;
mod fixtures;

//! Integration tests of kappe-fe: the acceptance checks A1–A12 of
//! `../shared/reference/buckling.md` §7 (one test binary, modules per topic).

mod common;
mod fixtures;

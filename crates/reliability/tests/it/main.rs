//! Integration tests of kappe_reliability; every tolerance is stated and justified where it is used.

mod common;
mod distributions;
mod errors;
mod form_closed_forms;
mod form_literature;
mod nataf;
mod sampling;
mod sorm;
mod spec;
mod system;

//! The top floor, **commands built on the run**: design studies ([`study`]), ceilings of many
//! bays ([`ceiling`]), the design loop ([`optimize`]), the least waits of a schedule
//! ([`least_waits`]), the two calibrations (BLF_min from prototypes, [`calibrate_blf`]; a
//! time-model parameter from buildability prints, [`calibrate_print`]), the buildability test
//! objects ([`buildability`]), the corrugation study ([`corrugation`]) and the example files
//! ([`templates`]).

pub mod buildability;
pub mod buildability_collapse;
pub mod buildability_reliability;
pub mod calibrate_blf;
pub mod calibrate_print;
pub mod ceiling;
pub mod corrugation;
pub mod least_waits;
pub mod optimize;
pub mod study;
pub mod templates;

//! One exit-status scheme for every command (README, `kappe --help`):
//!
//! | status | meaning |
//! |---|---|
//! | 0 | success |
//! | 1 | the design or study fails its checks (or some designs of a study failed or could not run) |
//! | 2 | usage or input error: bad arguments, a bad or empty input file, an output location Kappe refuses |
//! | 3 | internal error or an I/O failure (cannot write, a solver breakdown, a panic) |
//!
//! Commands return `Ok(ExitCode)` for 0 and 1; every error goes through [`status_of`], which
//! looks through the error chain for the first error whose kind it knows.

use std::process::ExitCode;

/// The design or study fails its checks.
pub const FAILS: u8 = 1;
/// Usage or input error.
pub const USAGE: u8 = 2;
/// Internal error or I/O failure.
pub const INTERNAL: u8 = 3;

/// Exit status for "the design (or study) fails its checks".
pub fn fails() -> ExitCode {
    ExitCode::from(FAILS)
}

/// A usage or input error found by the CLI itself (status 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Usage(pub String);

/// The status for an error: the first error in the chain of a known kind decides.
pub fn status_of(err: &anyhow::Error) -> u8 {
    for cause in err.chain() {
        if let Some(code) = status_of_cause(cause) {
            return code;
        }
    }
    INTERNAL
}

fn status_of_cause(cause: &(dyn std::error::Error + 'static)) -> Option<u8> {
    if cause.is::<Usage>() {
        return Some(USAGE);
    }
    kappe::class::class_of(cause).map(|class| match class {
        kappe::class::Class::Input => USAGE,
        kappe::class::Class::Fails => FAILS,
        kappe::class::Class::Internal => INTERNAL,
    })
}

/// Panics are internal errors: print the usual message, then exit with [`INTERNAL`] instead of
/// Rust's 101. A closed stdout (`kappe design --json | head`) ends quietly with 141
/// (128 + SIGPIPE), as Unix tools do.
pub fn install_panic_hook() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.contains("failed printing to stdout") && msg.contains("Broken pipe") {
            std::process::exit(141);
        }
        default(info);
        eprintln!("error: internal error (a bug in Kappe; please report it with the input)");
        std::process::exit(i32::from(INTERNAL));
    }));
}

/// Exit status after Ctrl-C (128 + SIGINT, as shells report it).
pub const INTERRUPTED: u8 = 130;

/// Ctrl-C says what happened before the process ends: outputs are swapped in only when
/// complete, so an interrupted run has changed nothing unless it had finished writing (the
/// hidden staging directory it leaves is removed by the next run).
pub fn install_interrupt_handler() {
    // Without a handler the default action still ends the process; only the message is lost.
    let _ = ctrlc::set_handler(|| {
        eprintln!(
            "\ninterrupted (Ctrl-C): Kappe stopped. An output is put in place only when it is \
             complete, so the output location holds the previous output (or nothing) unless \
             this run had already finished writing"
        );
        std::process::exit(i32::from(INTERRUPTED));
    });
}

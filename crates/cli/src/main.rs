//! `kappe`: design 3D-printed cap ceilings and plan the robot that prints them.
//!
//! The binary is thin on purpose: it parses arguments, calls the library crates,
//! writes files atomically and prints. Each subcommand lives in `cmd/<name>.rs`.

mod cmd;
mod exit;
mod input;
mod output;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "kappe", version, about, long_about = None, after_help = EXIT_HELP)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Combinatorial Equilibrium Modeling: solve or form-find a topology (kappe.cem.topology JSON).
    #[command(subcommand)]
    Cem(cmd::cem::CemCommand),
    /// Shell finite elements: linear statics and linear buckling of a mesh (fixture JSON format).
    #[command(subcommand)]
    Fe(cmd::fe::FeCommand),
    /// UR10e kinematics and robot plans.
    #[command(subcommand)]
    Robot(cmd::robot::RobotCommand),
    /// Design a cap ceiling: form-find every print state, analyse, write outputs.
    Design(cmd::design::DesignArgs),
    /// Write the designer: one offline page with the design's parameters as sliders, the cap in 3D and its checks live.
    Designer(cmd::designer::DesignerArgs),
    /// Write a commented example file: a design (default), or --kind study|prototypes|optimize|buildability|ceiling|moving|corrugated.
    Init(cmd::init::InitArgs),
    /// Design study: run a grid or list of design variations (`kappe study merge` joins shards).
    Study(cmd::study::StudyCommand),
    /// Derive BLF_min (or the effective E) from printed prototypes that stood or failed.
    Calibrate(cmd::calibrate::CalibrateArgs),
    /// The least print time (waits per layer) for which every state passes the green-state checks.
    Schedule(cmd::schedule::ScheduleArgs),
    /// Buildability of a test object (wall or cylinder): check every layer count with the green-state time model.
    Buildability(cmd::buildability::BuildabilityArgs),
    /// The design loop: vary the free parameters within bounds to meet every constraint with the least material.
    Optimize(cmd::optimize::OptimizeArgs),
    /// Corrugated caps: the governing buckling factor per kg and per print minute over a grid of wave amplitudes and wavelengths, against the smooth cap.
    Corrugation(cmd::corrugation::CorrugationArgs),
}

/// The exit-status scheme, shown by `kappe --help` (see `exit.rs`).
const EXIT_HELP: &str = "Exit status: 0 success; 1 the design or study fails its checks (or some \
designs failed); 2 usage or input error (nothing is written); 3 internal error or I/O failure.";

fn main() -> ExitCode {
    exit::install_panic_hook();
    exit::install_interrupt_handler();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Cem(c) => cmd::cem::run(c),
        Command::Fe(c) => cmd::fe::run(c),
        Command::Robot(c) => cmd::robot::run(c),
        Command::Design(a) => cmd::design::run(a),
        Command::Designer(a) => cmd::designer::run(a),
        Command::Init(a) => cmd::init::init(a),
        Command::Study(c) => cmd::study::run(c),
        Command::Calibrate(a) => cmd::calibrate::run(a),
        Command::Optimize(a) => cmd::optimize::run(a),
        Command::Buildability(a) => cmd::buildability::run(a),
        Command::Schedule(a) => cmd::schedule::run(a),
        Command::Corrugation(a) => cmd::corrugation::run(a),
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            eprintln!("error: {err}");
            for cause in err.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::from(exit::status_of(&err))
        }
    }
}

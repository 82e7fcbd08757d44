//! One module per subcommand; each exposes `run(args) -> anyhow::Result<u8>` (the exit code)
//! and lists every file it reads and writes (`files`), which [`run`] checks together
//! before the command starts ([`goniofit::io::FileSet`]).

pub mod args;
pub mod bench;
pub mod convert;
pub mod design;
pub mod eval;
pub mod figures;
pub mod fit;
pub mod fit_args;
pub mod fit_outputs;
pub mod heartbeat;
pub mod plot;
pub mod recover;
pub mod render;
pub mod signals;
pub mod stages;
pub mod synth;

use crate::cli::{Cli, Command};
use goniofit::io::FileSet;

impl Command {
    /// Every file the command reads and writes, with the option naming it.
    fn files(&self) -> anyhow::Result<FileSet> {
        Ok(match self {
            Command::Eval(a) => a.files(),
            Command::Fit(a) => a.files(),
            Command::Plot(a) => a.files(),
            Command::Synth(a) => a.files(),
            Command::Recover(_) => FileSet::new().stdout(),
            Command::Bench(a) => a.files(),
            Command::Convert(a) => a.files(),
            Command::Design(a) => a.files(),
            Command::Render(a) => a.files(),
            Command::Figures(a) => a.files(),
        })
    }
}

/// Run the parsed command line, once its files passed [`FileSet::check`] (no output is an
/// input or another output, every output path can be written): nothing is read or written
/// before.
pub fn run(cli: Cli) -> anyhow::Result<u8> {
    cli.command.files()?.check()?;
    match cli.command {
        Command::Eval(a) => eval::run(a),
        Command::Fit(a) => fit::run(*a),
        Command::Plot(a) => plot::run(a),
        Command::Synth(a) => synth::run(*a),
        Command::Recover(a) => recover::run(*a),
        Command::Bench(a) => bench::run(*a),
        Command::Convert(a) => convert::run(a),
        Command::Design(a) => design::run(*a),
        Command::Render(a) => render::run(a),
        Command::Figures(a) => figures::run(a),
    }
}

/// Whether `e` is a stop request that came before anything could be reported
/// ([`goniofit::Error::Stopped`] anywhere in its chain).
pub fn is_stopped(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<goniofit::Error>(),
            Some(goniofit::Error::Stopped(_))
        )
    })
}

/// Exit code for an error: 3 for a stop with nothing to report ([`is_stopped`]), 2 for the
/// user's input or usage, 1 for internal failures.
pub fn exit_code_of(e: &anyhow::Error) -> u8 {
    if is_stopped(e) {
        return 3;
    }
    match e.downcast_ref::<goniofit::Error>() {
        Some(ge) if !ge.is_user_error() => 1,
        Some(_) => 2,
        None => {
            if e.chain().any(|c| {
                c.downcast_ref::<goniofit::Error>()
                    .is_some_and(|g| g.is_user_error())
            }) {
                2
            } else {
                1
            }
        }
    }
}

//! The goniofit command line: parse arguments, run, map the outcome to an exit code.
//! Exit codes: 0 success, 1 internal failure, 2 bad usage or bad input, 3 a fit that ran
//! but did not converge (its report is still printed).

mod cli;
mod commands;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = match cli::Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match commands::run(cli) {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            eprintln!("goniofit: error: {e:#}");
            ExitCode::from(commands::exit_code_of(&e))
        }
    }
}

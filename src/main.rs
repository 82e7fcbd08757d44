//! The goniofit command line: parse arguments, run, map the outcome to an exit code.
//! Exit codes: 0 success, 1 internal failure, 2 bad usage or bad input, 3 a fit that ran
//! but did not converge or was stopped (its report is printed when it has a point).

mod cli;
mod commands;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    // Ctrl-C, SIGTERM, SIGHUP: a running fit stops and reports (exit 3); anything else ends
    // with exit 130 and leaves no unfinished output file behind.
    commands::signals::install();
    let cli = match cli::Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match cli::run(cli) {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            // A stop with nothing to report is no error: it says what was stopped (exit 3).
            let kind = if commands::is_stopped(&e) {
                ""
            } else {
                "error: "
            };
            eprintln!("goniofit: {kind}{}", error_chain(&e));
            ExitCode::from(commands::exit_code_of(&e))
        }
    }
}

/// The error and its causes, joined by ": ", leaving out a cause whose text the message
/// already contains (errors that show their source in their own message).
fn error_chain(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if !out.contains(&text) {
            if !out.is_empty() {
                out.push_str(": ");
            }
            out.push_str(&text);
        }
    }
    out
}

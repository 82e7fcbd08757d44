//! The goniofit command line ([`goniofit::cli::main`]).

fn main() -> std::process::ExitCode {
    goniofit::cli::main()
}

//! One module per subcommand; each exposes `run(args) -> anyhow::Result<u8>` (the exit code)
//! and lists every file it reads and writes (`files`), which `cli::run` checks together
//! before the command starts ([`crate::io::FileSet`]).

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

/// Whether `e` is a stop request that came before anything could be reported
/// ([`crate::Error::Stopped`] anywhere in its chain).
pub fn is_stopped(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<crate::Error>(),
            Some(crate::Error::Stopped(_))
        )
    })
}

/// Exit code for an error: 3 for a stop with nothing to report ([`is_stopped`]), 2 for the
/// user's input or usage, 1 for internal failures.
pub fn exit_code_of(e: &anyhow::Error) -> u8 {
    if is_stopped(e) {
        return 3;
    }
    match e.downcast_ref::<crate::Error>() {
        Some(ge) if !ge.is_user_error() => 1,
        Some(_) => 2,
        None => {
            if e.chain().any(|c| {
                c.downcast_ref::<crate::Error>()
                    .is_some_and(|g| g.is_user_error())
            }) {
                2
            } else {
                1
            }
        }
    }
}

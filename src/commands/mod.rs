//! One module per subcommand; each exposes `run(args) -> anyhow::Result<u8>` (the exit code)
//! and lists every file it reads and writes (`files`), which `cli::run` checks together
//! before the command starts ([`crate::io::FileSet`]).

pub(crate) mod args;
pub(crate) mod bench;
pub(crate) mod convert;
pub(crate) mod design;
pub(crate) mod eval;
pub(crate) mod figures;
pub(crate) mod fit;
pub(crate) mod fit_args;
pub(crate) mod fit_outputs;
pub(crate) mod heartbeat;
pub(crate) mod memory;
pub(crate) mod plot;
pub(crate) mod recover;
pub(crate) mod render;
pub(crate) mod signals;
pub(crate) mod stages;
pub(crate) mod synth;

/// Whether `e` is a stop request that came before anything could be reported
/// ([`crate::error::Error::Stopped`] anywhere in its chain).
pub(crate) fn is_stopped(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<crate::error::Error>(),
            Some(crate::error::Error::Stopped(_))
        )
    })
}

/// Exit code for an error: 3 for a stop with nothing to report ([`is_stopped`]), 2 for the
/// user's input or usage, 1 for internal failures.
pub(crate) fn exit_code_of(e: &anyhow::Error) -> u8 {
    if is_stopped(e) {
        return 3;
    }
    match e.downcast_ref::<crate::error::Error>() {
        Some(ge) if !ge.is_user_error() => 1,
        Some(_) => 2,
        None => {
            if e.chain().any(|c| {
                c.downcast_ref::<crate::error::Error>()
                    .is_some_and(|g| g.is_user_error())
            }) {
                2
            } else {
                1
            }
        }
    }
}

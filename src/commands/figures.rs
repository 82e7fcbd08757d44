//! `goniofit figures`: regenerate the paper's Figures 4–7 as PNG and SVG.

use crate::io::FileSet;
use anyhow::Context;
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct FiguresArgs {
    /// Output folder (created if needed); writes figure4.png, figure4.svg, … figure7.svg.
    #[arg(long)]
    pub out: PathBuf,
}

impl FiguresArgs {
    /// The figures in the `--out` folder, and their names on standard output.
    pub(crate) fn files(&self) -> FileSet {
        FileSet::new()
            .pictures("--out", &self.out, &crate::plot::figures::FIGURES)
            .stdout()
    }
}

pub(crate) fn run(args: FiguresArgs) -> anyhow::Result<u8> {
    let paths = crate::plot::figures::write_all(&args.out)
        .with_context(|| format!("writing figures into {}", crate::io::shown(&args.out)))?;
    for p in paths {
        crate::io::print_stdout(&format!("{}\n", crate::io::shown(&p)))?;
    }
    Ok(0)
}

//! `goniofit figures`: regenerate the paper's Figures 4–7 as PNG and SVG.

use anyhow::Context;
use clap::Args;
use goniofit::io::FileSet;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct FiguresArgs {
    /// Output folder (created if needed); writes figure4.png, figure4.svg, … figure7.svg.
    #[arg(long)]
    pub out: PathBuf,
}

impl FiguresArgs {
    /// The figures in the `--out` folder, and their names on standard output.
    pub fn files(&self) -> FileSet {
        FileSet::new()
            .pictures("--out", &self.out, &goniofit::plot::figures::FIGURES)
            .stdout()
    }
}

pub fn run(args: FiguresArgs) -> anyhow::Result<u8> {
    let paths = goniofit::plot::figures::write_all(&args.out)
        .with_context(|| format!("writing figures into {}", goniofit::io::shown(&args.out)))?;
    for p in paths {
        goniofit::io::print_stdout(&format!("{}\n", goniofit::io::shown(&p)))?;
    }
    Ok(0)
}

//! `goniofit eval`: a model's values at the angles of a CSV file.

use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Model name: kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert, lambert-specular.
    #[arg(long)]
    pub model: String,
    /// Parameters as name=value pairs, e.g. sigma=0.3,T=2,scale=1.
    #[arg(long)]
    pub params: String,
    /// Input CSV with columns theta_i, theta_r, phi_r (others are passed through).
    pub file: PathBuf,
}

pub fn run(_args: EvalArgs) -> anyhow::Result<u8> {
    anyhow::bail!("goniofit eval: not built yet")
}

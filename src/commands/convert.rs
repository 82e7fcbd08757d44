//! `goniofit convert`: the samples `fit` would fit, from any format goniofit reads, as a
//! CSV table that goniofit (and any spreadsheet) reads back.
//!
//! Columns: `theta_i, theta_r, phi_r` (degrees, goniofit's convention: φr = 0 the
//! forward/specular side), `L` (the measured value), then when the input has them
//! `sigma_L` or `weight`, `wavelength` (per sample, in the unit of the line
//! `# wavelength unit: …` when the file states one) and `group` (the channel). A BRDF input
//! opens with the comment `# quantity: brdf`, so reading the table back gives the same
//! quantity. Values are written with full precision (shortest round-tripping decimal).

use crate::geometry::Quantity;
use crate::io::{self, FileSet};
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct ConvertArgs {
    /// The channel to convert: an ASTM channel (550nm), an RGL channel (r, g, b), a CSV
    /// group or wavelength; `all` for every channel.
    #[arg(long)]
    pub channel: Option<String>,
    /// MERL tables: every K-th θd and φd cell (K² fewer samples; default all).
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=90))]
    pub subsample: usize,
    /// Angles are in radians (CSV input; other formats state their unit).
    #[arg(long)]
    pub radians: bool,
    /// θr < 0 means θr = |θr| at φr + 180° (CSV input).
    #[arg(long)]
    pub signed_theta_r: bool,
    /// Column mappings role=name,... (CSV input).
    #[arg(long, value_name = "ROLE=NAME,...")]
    pub columns: Vec<String>,
    /// Write the table here (atomically); `-` or none: standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// A measurement file: CSV, ASTM E1392, RGL `.bsdf`, MERL `.binary` or ALTA data.
    pub file: PathBuf,
}

impl ConvertArgs {
    /// The input file; the table to `--out` or standard output.
    pub(crate) fn files(&self) -> FileSet {
        super::args::table_files(&self.file, self.out.as_deref())
    }
}

pub(crate) fn run(args: ConvertArgs) -> anyhow::Result<u8> {
    let opts = super::args::table_read_options(
        &args.columns,
        (args.radians, args.signed_theta_r),
        (args.channel.clone(), args.subsample),
        true,
    )?;
    let ds = io::read_dataset_columns(&args.file, &opts)?;
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from("-"));
    io::write_atomic(&out, |w: &mut dyn Write| write_table(w, &ds))?;
    Ok(0)
}

/// The table of the module docs.
fn write_table(w: &mut dyn Write, ds: &io::Dataset) -> std::io::Result<()> {
    if ds.quantity == Some(Quantity::Brdf) {
        writeln!(w, "# quantity: brdf")?;
    }
    if let (Some(_), Some(unit)) = (&ds.wavelength, &ds.wavelength_unit) {
        writeln!(w, "# wavelength unit: {unit}")?;
    }
    let mut headers: Vec<String> = ["theta_i", "theta_r", "phi_r", "L"]
        .map(String::from)
        .to_vec();
    let extra: [(&str, Option<&Vec<f64>>); 3] = [
        ("sigma_L", ds.sigma_l.as_ref()),
        (
            "weight",
            if ds.sigma_l.is_some() {
                None
            } else {
                ds.weight.as_ref()
            },
        ),
        ("wavelength", ds.wavelength.as_ref()),
    ];
    headers.extend(
        extra
            .iter()
            .filter(|(_, v)| v.is_some())
            .map(|(n, _)| n.to_string()),
    );
    if ds.channel.is_some() {
        headers.push("group".into());
    }
    io::write_record(w, &headers)?;
    let value = ds.value.as_deref().unwrap_or_default();
    for (k, s) in ds.samples.iter().enumerate() {
        let mut row = vec![
            io::format_value(s.theta_i.to_degrees()),
            io::format_value(s.theta_r.to_degrees()),
            io::format_value(s.phi_r.to_degrees()),
            io::format_value(value[k]),
        ];
        row.extend(
            extra
                .iter()
                .filter_map(|(_, v)| v.map(|v| io::format_value(v[k]))),
        );
        if let Some(c) = &ds.channel {
            row.push(c[k].clone());
        }
        io::write_record(w, &row)?;
    }
    Ok(())
}

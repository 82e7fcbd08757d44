//! The `goniofit` command end to end: each module runs the built binary on files and checks
//! its outputs, exit codes and messages, one command or one behaviour per module.

#[path = "../common/mod.rs"]
mod common;

mod adequacy;
mod batch_page;
mod convert;
mod csv_quantity;
mod degenerate;
mod design;
mod doc_commands;
mod eval;
mod finite_output;
mod fit;
mod fresnel_fit;
mod hostile_params;
mod kbs_rough;
mod option_values_sweep;
mod output_files;
mod output_set;
mod pictures;
mod report;
mod robust;
mod specular_width;
mod summaries;
mod synth;
mod validity;

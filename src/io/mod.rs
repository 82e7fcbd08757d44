//! Reading measurements and writing tables.
//!
//! [`read_dataset`] reads either a CSV table ([`csv`]) or an ASTM E1392 file ([`astm`]) into
//! a [`Dataset`]: validated angles in our convention (docs/conventions.md: radians, θi ∈ [0, π/2),
//! θr ∈ [0, π/2], φr from the plane of incidence, φr = 0 the forward/specular side), the
//! measured values, and the raw rows for pass-through output.
//!
//! Format detection: a file that starts with the bytes `tensor_file\0` or is named
//! `*.bsdf` is an RGL measured BRDF ([`rgl`]); a file of MERL's size whose first 12 bytes
//! are the dimensions 90, 90, 180, or one named `*.binary`, is a MERL BRDF ([`merl`]); a
//! text file whose first non-blank line is `#DIM` is ALTA data ([`alta`]). A file is ASTM
//! E1392 when its extension is `.astm` (any case), or when
//! its first non-blank line starts with an upper-case `KEY` token (e.g. `LAB_NAME ...`) and
//! some line starts with `VARS`. Everything else is CSV.
//!
//! Writing ([`output`]): [`write_atomic`] replaces a regular file through a temporary in
//! its folder and a rename, so a failed or interrupted write leaves nothing behind, and
//! writes devices, FIFOs and `-` (stdout) straight through; [`write_csv`] writes a table
//! that way; [`FileSet`] checks every file of a command together before anything is
//! written (no output is an input or another output).
//!
//! ```
//! use goniofit::{read, ReadOptions};
//! let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/cornell/garnet_red.astm");
//! let opts = ReadOptions { channel: Some("550nm".into()), require_value: true, ..Default::default() };
//! let ds = read(&path, &opts)?;
//! assert_eq!(ds.len(), 1439);
//! assert_eq!(ds.wavelength.as_ref().unwrap()[0], 550.0); // nm, from the channel name
//! # Ok::<(), goniofit::Error>(())
//! ```
//!
//! Every reading error is an [`Error::Input`](crate::error::Error::Input) (file, 1-based line,
//! column, offending value), an [`Error::File`](crate::error::Error::File) (the whole file: empty,
//! no data rows, missing column) or an [`Error::Io`](crate::error::Error::Io); no input makes the
//! readers panic (proptest in `tests/lib/io.rs`).
//!
//! Where the parts are: `read.rs` the reading of a file or of bytes, `sniff.rs` the format
//! from the extension and the first bytes, `dataset.rs` the [`Dataset`] and
//! [`ReadOptions`], `channel.rs` `--channel` on a CSV dataset, `values.rs` numbers, angles
//! and lengths in files, `text.rs` CSV tables written (names as printed, [`shown`] and
//! [`shown_text`], are the error layer's); one file or folder per format ([`csv`],
//! [`astm`], [`rgl`], [`merl`], [`alta`]; [`arrays`] for arrays handed over by a program),
//! [`output`] and [`files`] for writing.

pub(crate) mod alta;
pub(crate) mod arrays;
pub(crate) mod astm;
mod channel;
pub(crate) mod csv;
mod dataset;
pub(crate) mod files;
pub(crate) mod merl;
pub(crate) mod output;
mod quantity;
mod read;
pub(crate) mod rgl;
mod sniff;
mod text;
mod values;

pub(crate) use files::FileSet;
pub(crate) use output::{print_stdout, write_atomic, write_bytes};

pub(crate) use crate::error::{shown, shown_text};
pub(crate) use channel::select_csv_channel;
pub(crate) use dataset::empty_brdf;
pub use dataset::{Dataset, ReadOptions};
#[cfg(test)]
pub(crate) use read::read_bytes;
pub(crate) use read::read_dataset;
pub use read::read_dataset_columns;
pub(crate) use read::read_dataset_with;
pub(crate) use text::{write_csv, write_record};
pub use values::parse_length;
pub(crate) use values::{check_angles, parse_finite};
pub(crate) use values::{format_value, nm_per, wavelength_nm_of_channel};

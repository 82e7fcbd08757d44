//! MERL BRDF database files (`.binary`, Matusik et al. 2003, "A Data-Driven Reflectance
//! Model").
//!
//! Layout (little-endian): three i32 dimensions — 90 (θh), 90 (θd), 180 (φd) — then
//! 3 × 1,458,000 f64: the red table, then green, then blue, each indexed
//! `φd + 180·(θd + 90·θh)` by cell. A stored number times its channel's scale (red 1/1500,
//! green 1.15/1500, blue 1.66/1500) is the BRDF in 1/sr; a negative number marks a cell
//! that was not measured and is skipped.
//!
//! Cells follow the reference reader's lookup (`BRDFRead.cpp`): θh index
//! ⌊√(θh/(π/2)) · 90⌋, θd index ⌊θd/(π/2) · 90⌋, φd index ⌊φd/π · 180⌋ (φd + π when φd < 0).
//! goniofit places each cell's sample at the cell's centre in those index coordinates:
//! θh = ((i + ½)/90)² π/2, θd = (j + ½)/90 · π/2, φd = (k + ½)/180 · π. The half vector is
//! at azimuth 0; the incident direction is the difference vector rotated by θh about the
//! y axis, the outgoing its mirror about the half vector. A cell whose directions are not
//! both above the horizon is skipped. Angles are then expressed in goniofit's convention
//! (ωi at azimuth 0, φr = φo − φi − π so that the mirror direction is φr = 0).
//!
//! Reading is streamed: the three channel tables are read one after the other through a
//! 64 KiB buffer into one table, and only the selected channels' measured cells are kept
//! (with `stride` k > 1, every k-th θd and φd cell). `lines` holds each sample's 1-based
//! cell number; channel labels are kept only when more than one channel is read.

use super::{Dataset, ReadOptions};
use crate::error::{Error, Result};
use crate::geometry::{wrap_phi, Sample};
use std::f64::consts::{FRAC_PI_2, PI};
use std::io::Read;
use std::path::Path;

/// Cells along θh, θd and φd.
pub(crate) const DIMS: [usize; 3] = [90, 90, 180];
/// Cells per channel table.
pub(crate) const CELLS: usize = DIMS[0] * DIMS[1] * DIMS[2];
/// The channel scales of the reference reader (stored number × scale = BRDF in 1/sr).
pub(crate) const SCALES: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];
/// Bytes of a MERL file: the dimensions and three tables of f64.
pub(crate) const FILE_BYTES: u64 = 12 + 3 * 8 * CELLS as u64;

/// The centre of cell (θh index, θd index, φd index) in the lookup's coordinates (rad).
pub(crate) fn cell_centre(i: usize, j: usize, k: usize) -> (f64, f64, f64) {
    let u = (i as f64 + 0.5) / 90.0;
    (
        u * u * FRAC_PI_2,
        (j as f64 + 0.5) / 90.0 * FRAC_PI_2,
        (k as f64 + 0.5) / 180.0 * PI,
    )
}

/// Incident and outgoing unit vectors of half/difference angles (half vector at azimuth 0).
pub(crate) fn directions(theta_h: f64, theta_d: f64, phi_d: f64) -> ([f64; 3], [f64; 3]) {
    let d = [
        theta_d.sin() * phi_d.cos(),
        theta_d.sin() * phi_d.sin(),
        theta_d.cos(),
    ];
    let (s, c) = theta_h.sin_cos();
    let wi = [c * d[0] + s * d[2], d[1], -s * d[0] + c * d[2]];
    let h = [s, 0.0, c];
    let dot = wi[0] * h[0] + wi[2] * h[2];
    let wo = [2.0 * dot * h[0] - wi[0], -wi[1], 2.0 * dot * h[2] - wi[2]];
    (wi, wo)
}

/// The half/difference angles (θh, θd, φd) of a pair of unit vectors, as the reference
/// reader's `std_coords_to_half_diff_coords`.
#[cfg(test)]
pub(crate) fn half_diff(wi: [f64; 3], wo: [f64; 3]) -> (f64, f64, f64) {
    let h = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
    let n = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let h = h.map(|v| v / n);
    let theta_h = h[2].clamp(-1.0, 1.0).acos();
    let phi_h = h[1].atan2(h[0]);
    // Rotate wi by −φh about z, then by −θh about y.
    let (s, c) = (-phi_h).sin_cos();
    let t = [c * wi[0] - s * wi[1], s * wi[0] + c * wi[1], wi[2]];
    let (s, c) = (-theta_h).sin_cos();
    let d = [c * t[0] + s * t[2], t[1], -s * t[0] + c * t[2]];
    (theta_h, d[2].clamp(-1.0, 1.0).acos(), d[1].atan2(d[0]))
}

/// The sample (goniofit's convention) of a cell centre, when both directions are above
/// the horizon.
fn cell_sample(i: usize, j: usize, k: usize) -> Option<Sample> {
    let (th, td, pd) = cell_centre(i, j, k);
    let (wi, wo) = directions(th, td, pd);
    if wi[2] <= 1e-9 || wo[2] <= 0.0 {
        return None;
    }
    let phi_i = wi[1].atan2(wi[0]);
    Some(Sample {
        theta_i: wi[0].hypot(wi[1]).atan2(wi[2]),
        theta_r: wo[0].hypot(wo[1]).atan2(wo[2]).min(FRAC_PI_2),
        phi_r: wrap_phi(wo[1].atan2(wo[0]) - phi_i - PI),
    })
}

/// Whether `bytes` (a file's start) and its length look like a MERL file.
pub(crate) fn is_merl(head: &[u8], len: u64) -> bool {
    head.len() >= 12
        && len == FILE_BYTES
        && head[..12]
            .chunks_exact(4)
            .zip(DIMS)
            .all(|(b, d)| i32::from_le_bytes(b.try_into().unwrap()) == d as i32)
}

/// Read a MERL file from `reader` (`len` bytes): the measured cells of the channels
/// `opts.channel` selects (`r`, `g`, `b` or `all`; required), every `stride`-th θd and φd
/// cell (1: all), as BRDF (1/sr) with the channels' nominal wavelengths (nm, as RGL's).
pub(crate) fn read(
    path: &Path,
    mut reader: impl Read,
    len: u64,
    opts: &ReadOptions,
    stride: usize,
) -> Result<Dataset> {
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    if len < 12 {
        return Err(size_error(path, len));
    }
    let mut head = [0u8; 12];
    reader.read_exact(&mut head).map_err(io_err)?;
    for (k, (b, d)) in head.chunks_exact(4).zip(DIMS).enumerate() {
        let got = i32::from_le_bytes(b.try_into().unwrap());
        if got != d as i32 {
            return Err(Error::file(
                path,
                format!(
                    "byte {}: dimension {k}: expected {d} (MERL 90 × 90 × 180), found {got}",
                    4 * k
                ),
            ));
        }
    }
    if len != FILE_BYTES {
        return Err(size_error(path, len));
    }
    let selected = super::rgl::select_channels(path, opts.channel.as_deref())?;
    let stride = stride.max(1);
    // No rows (the columns say everything); channel labels only when more than one
    // channel is read, so that one channel costs 48 bytes a cell.
    let mut ds = super::empty_brdf(path, selected.len() > 1, false, true);
    let mut table = vec![0f64; CELLS];
    let mut buf = vec![0u8; 1 << 16];
    for c in 0..3 {
        read_table(&mut reader, &mut buf, &mut table).map_err(io_err)?;
        if selected.contains(&c) {
            push_channel(&mut ds, &table, c, stride);
        }
    }
    if ds.samples.is_empty() {
        return Err(Error::file(
            path,
            "no measured cell: every selected value is negative or not finite".into(),
        ));
    }
    ds.shrink_to_fit();
    Ok(ds)
}

/// Append channel `c`'s measured cells (every `stride`-th θd and φd cell).
fn push_channel(ds: &mut Dataset, table: &[f64], c: usize, stride: usize) {
    for i in 0..DIMS[0] {
        for j in (0..DIMS[1]).step_by(stride) {
            for k in (0..DIMS[2]).step_by(stride) {
                let cell = k + DIMS[2] * (j + DIMS[1] * i);
                let v = table[cell];
                if !(v.is_finite() && v >= 0.0) {
                    continue;
                }
                let Some(s) = cell_sample(i, j, k) else {
                    continue;
                };
                ds.samples.push(s);
                ds.lines.push(cell + 1);
                ds.value.as_mut().unwrap().push(v * SCALES[c]);
                ds.wavelength
                    .as_mut()
                    .unwrap()
                    .push(super::rgl::NOMINAL_NM[c]);
                if let Some(ch) = ds.channel.as_mut() {
                    ch.push(super::rgl::CHANNELS[c].to_string());
                }
            }
        }
    }
}

/// The error for a file of the wrong size.
fn size_error(path: &Path, len: u64) -> Error {
    Error::file(
        path,
        format!(
            "expected {FILE_BYTES} bytes (12 + 3 tables of {CELLS} f64: a MERL file), found {len}"
        ),
    )
}

/// One channel table of f64, read through `buf`.
fn read_table(reader: &mut impl Read, buf: &mut [u8], table: &mut [f64]) -> std::io::Result<()> {
    let per = buf.len() / 8;
    for chunk in table.chunks_mut(per) {
        let bytes = &mut buf[..chunk.len() * 8];
        reader.read_exact(bytes)?;
        for (v, b) in chunk.iter_mut().zip(bytes.chunks_exact(8)) {
            *v = f64::from_le_bytes(b.try_into().unwrap());
        }
    }
    Ok(())
}

/// Read a MERL file by path (see [`read`]).
#[cfg(test)]
pub(crate) fn read_path(path: &Path, opts: &ReadOptions, stride: usize) -> Result<Dataset> {
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io_err)?;
    let len = file.metadata().map_err(io_err)?.len();
    read(
        path,
        std::io::BufReader::with_capacity(1 << 16, file),
        len,
        opts,
        stride,
    )
}

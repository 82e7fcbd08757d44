//! The dataset type: what every reader returns ([`Dataset`]), how a file is read
//! ([`ReadOptions`]), and the empty BRDF table the binary and ALTA readers fill.

use super::rgl;
use crate::geometry::{Quantity, Sample};
use std::path::{Path, PathBuf};

/// How to read a file.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Angles in radians (CSV); ASTM files are always radians.
    pub radians: bool,
    /// θr < 0 means θr = |θr| on the opposite side (φr + 180°); at φr = 0 that is φr = 180°.
    pub signed_theta_r: bool,
    /// `--columns role=name` mappings; roles: theta_i, theta_r, phi_r, L, weight, sigma_L,
    /// wavelength, group (case-insensitive; `value` is accepted for `L`). CSV only.
    pub columns: Vec<(String, String)>,
    /// Whether column L (the measured value) must exist (fit: yes; eval: no).
    pub require_value: bool,
    /// One channel, or `all`. ASTM: a channel name such as `550nm`. CSV: a `group` label
    /// when the file has a `group` column, otherwise a wavelength (`0.532`, in the file's
    /// unit, or `532nm`) selecting the rows of that `wavelength`; `all` on a CSV without a
    /// `group` column makes each wavelength a channel (see `super::select_csv_channel`).
    pub channel: Option<String>,
    /// MERL tables: keep every k-th θd and φd cell (k² fewer samples; 0 or 1 keeps all).
    /// Other formats refuse k > 1.
    pub subsample: usize,
}

/// A dataset as read: angles validated, values parsed, raw rows kept for pass-through.
#[derive(Debug, Clone)]
pub struct Dataset {
    /// The file as named by the caller (for arrays handed over by a program, the name it
    /// gave them); messages about the data name it.
    pub path: PathBuf,
    /// Column names of `rows` (as in the file, surrounding whitespace removed).
    pub headers: Vec<String>,
    /// Raw fields per sample, for pass-through output.
    pub rows: Vec<Vec<String>>,
    /// 1-based source line of each sample.
    pub lines: Vec<usize>,
    /// Sample angles in radians, in the convention of docs/conventions.md.
    pub samples: Vec<Sample>,
    /// Measured L (or BRDF).
    pub value: Option<Vec<f64>>,
    /// Per-sample weight w (from `weight`, or 1/sigma_L²).
    pub weight: Option<Vec<f64>>,
    /// Standard uncertainty of the value, if given.
    pub sigma_l: Option<Vec<f64>>,
    /// Per-sample wavelength (a `wavelength` column in the file's unit, or from an ASTM
    /// channel name: `550nm` → 550, in nm).
    pub wavelength: Option<Vec<f64>>,
    /// Unit of `wavelength` when the file states it: `nm` for ASTM channel names, `µm` for
    /// the NIST PTFE layout; None for a plain `wavelength` column (unit unknown).
    pub wavelength_unit: Option<String>,
    /// Where `wavelength` comes from, in the report's words (e.g. `channel name`, `nominal
    /// wavelength of the sRGB channel`); None for a `wavelength` column.
    pub wavelength_origin: Option<&'static str>,
    /// Per-sample channel/group label (ASTM channel, or a `group` column).
    pub channel: Option<Vec<String>>,
    /// The measured quantity the file states (ASTM `MEAS_NAME BRDF`, NIST `f_r11`, a CSV
    /// `# quantity: brdf` comment or `brdf` value column), if any.
    pub quantity: Option<Quantity>,
}

impl Dataset {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether there are no samples (never true for a dataset [`crate::read`] returns).
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The distinct channel labels in first-appearance order (empty without channels).
    pub fn channel_names(&self) -> Vec<String> {
        self.channel_groups()
            .into_iter()
            .map(|(name, _)| name)
            .collect()
    }

    /// Every distinct channel label (first-appearance order) with the indices of its
    /// samples (ascending), found in one pass: O(n) for n samples however many groups
    /// (a texel batch has thousands). Empty without channels.
    pub fn channel_groups(&self) -> Vec<(String, Vec<usize>)> {
        let mut out: Vec<(String, Vec<usize>)> = Vec::new();
        let mut slot: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
        for (i, c) in self.channel.iter().flatten().enumerate() {
            let k = *slot.entry(c.as_str()).or_insert_with(|| {
                out.push((c.clone(), Vec::new()));
                out.len() - 1
            });
            out[k].1.push(i);
        }
        out
    }

    /// The samples at `idx` (in that order), every per-sample vector subset alike; used for
    /// per-channel fits. Indices must be `< self.len()`.
    pub fn subset(&self, idx: &[usize]) -> Dataset {
        fn pick<T: Clone>(v: &[T], idx: &[usize]) -> Vec<T> {
            idx.iter().map(|&i| v[i].clone()).collect()
        }
        Dataset {
            path: self.path.clone(),
            headers: self.headers.clone(),
            rows: if self.rows.is_empty() {
                Vec::new()
            } else {
                pick(&self.rows, idx)
            },
            lines: pick(&self.lines, idx),
            samples: pick(&self.samples, idx),
            value: self.value.as_deref().map(|v| pick(v, idx)),
            weight: self.weight.as_deref().map(|v| pick(v, idx)),
            sigma_l: self.sigma_l.as_deref().map(|v| pick(v, idx)),
            wavelength: self.wavelength.as_deref().map(|v| pick(v, idx)),
            wavelength_unit: self.wavelength_unit.clone(),
            wavelength_origin: self.wavelength_origin,
            channel: self.channel.as_deref().map(|v| pick(v, idx)),
            quantity: self.quantity,
        }
    }

    /// `other`'s samples (read with the same columns, its lines numbered from 1 where
    /// line `first_line` of this dataset's file is) moved after this dataset's; `other` is
    /// left empty with its allocations.
    pub(crate) fn append_from_line(&mut self, other: &mut Dataset, first_line: usize) {
        fn extend<T>(a: &mut Option<Vec<T>>, b: &mut Option<Vec<T>>) {
            if let (Some(a), Some(b)) = (a.as_mut(), b.as_mut()) {
                a.append(b);
            }
        }
        self.rows.append(&mut other.rows);
        let shift = first_line - 1;
        self.lines.extend(other.lines.drain(..).map(|l| l + shift));
        self.samples.append(&mut other.samples);
        extend(&mut self.value, &mut other.value);
        extend(&mut self.weight, &mut other.weight);
        extend(&mut self.sigma_l, &mut other.sigma_l);
        extend(&mut self.wavelength, &mut other.wavelength);
        extend(&mut self.channel, &mut other.channel);
    }

    /// No samples, every per-sample vector's allocation kept.
    pub(crate) fn clear(&mut self) {
        self.rows.clear();
        self.lines.clear();
        self.samples.clear();
        self.numbers().for_each(Vec::clear);
        if let Some(c) = self.channel.as_mut() {
            c.clear();
        }
    }

    /// Release the per-sample vectors' spare capacity (after reading).
    pub fn shrink_to_fit(&mut self) {
        self.rows.shrink_to_fit();
        self.lines.shrink_to_fit();
        self.samples.shrink_to_fit();
        self.numbers().for_each(Vec::shrink_to_fit);
        if let Some(c) = self.channel.as_mut() {
            c.shrink_to_fit();
        }
    }

    /// The per-sample number columns the file has (value, weight, σ_L, wavelength).
    fn numbers(&mut self) -> impl Iterator<Item = &mut Vec<f64>> {
        [
            &mut self.value,
            &mut self.weight,
            &mut self.sigma_l,
            &mut self.wavelength,
        ]
        .into_iter()
        .flatten()
    }

    /// Indices of the samples with channel label `name`.
    pub fn channel_indices(&self, name: &str) -> Vec<usize> {
        match &self.channel {
            Some(ch) => (0..ch.len()).filter(|&i| ch[i] == name).collect(),
            None => Vec::new(),
        }
    }
}

/// An empty BRDF table of a binary or ALTA file, without rows (its columns say
/// everything): a value column, `sigma_L` and weights when `sigma`, per-sample channel
/// labels when `labelled`, and per-sample wavelengths in nm when the channels are the
/// nominal sRGB ones (`rgb`).
pub(crate) fn empty_brdf(path: &Path, labelled: bool, sigma: bool, rgb: bool) -> Dataset {
    Dataset {
        path: path.to_path_buf(),
        headers: Vec::new(),
        rows: Vec::new(),
        lines: Vec::new(),
        samples: Vec::new(),
        value: Some(Vec::new()),
        weight: sigma.then(Vec::new),
        sigma_l: sigma.then(Vec::new),
        wavelength: rgb.then(Vec::new),
        wavelength_unit: rgb.then(|| "nm".to_string()),
        wavelength_origin: rgb.then_some(rgl::NOMINAL_ORIGIN),
        channel: labelled.then(Vec::new),
        quantity: Some(Quantity::Brdf),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::read_bytes;
    use std::path::Path;

    #[test]
    fn channel_groups_collect_interleaved_labels_in_first_appearance_order() {
        let text = b"theta_i,theta_r,phi_r,L,group\n10,20,0,1,b\n10,30,0,2,a\n10,40,0,3,b\n10,50,0,4,c\n10,60,0,5,a\n";
        let opts = ReadOptions {
            require_value: true,
            ..Default::default()
        };
        let ds = read_bytes(Path::new("t.csv"), text, &opts).unwrap();
        let groups = ds.channel_groups();
        let want: Vec<(String, Vec<usize>)> = vec![
            ("b".into(), vec![0, 2]),
            ("a".into(), vec![1, 4]),
            ("c".into(), vec![3]),
        ];
        assert_eq!(groups, want);
        assert_eq!(ds.channel_names(), ["b", "a", "c"]);
    }
}

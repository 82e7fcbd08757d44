//! Per-sample columns whose storage is shared: a [`Column`] of values, and a
//! [`PerSample`] quantity that is one value for all samples or a column.

use super::median;
use std::sync::Arc;

/// One per-sample column (of a [`Geometry`], or a fit's values), read as a slice. The
/// storage is shared:
/// cloning a column or a geometry, or slicing a contiguous range of samples
/// ([`Geometry::slice`]), copies nothing, so a fit's evaluation blocks and its input hold
/// one copy of the geometry between them.
///
/// [`Geometry`]: crate::geometry::Geometry
/// [`Geometry::slice`]: crate::geometry::Geometry::slice
#[derive(Debug, Clone, Default)]
pub struct Column {
    data: Arc<Vec<f64>>,
    start: usize,
    len: usize,
}

impl Column {
    /// The samples `range` of this column, sharing its storage; `range` must lie within
    /// the column.
    pub fn slice(&self, range: std::ops::Range<usize>) -> Column {
        assert!(
            range.start <= range.end && range.end <= self.len,
            "column slice out of range"
        );
        Column {
            data: self.data.clone(),
            start: self.start + range.start,
            len: range.end - range.start,
        }
    }
}

impl std::ops::Deref for Column {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.data[self.start..self.start + self.len]
    }
}

/// Writing through a column that shares its storage copies it first (copy on write):
/// the other holders keep the values they had.
impl std::ops::DerefMut for Column {
    fn deref_mut(&mut self) -> &mut [f64] {
        let (start, len) = (self.start, self.len);
        &mut Arc::make_mut(&mut self.data)[start..start + len]
    }
}

impl From<Vec<f64>> for Column {
    fn from(v: Vec<f64>) -> Self {
        let len = v.len();
        Column {
            data: Arc::new(v),
            start: 0,
            len,
        }
    }
}

impl FromIterator<f64> for Column {
    fn from_iter<I: IntoIterator<Item = f64>>(iter: I) -> Self {
        Vec::from_iter(iter).into()
    }
}

impl<'a> IntoIterator for &'a Column {
    type Item = &'a f64;
    type IntoIter = std::slice::Iter<'a, f64>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl PartialEq for Column {
    fn eq(&self, other: &Column) -> bool {
        **self == **other
    }
}

/// A per-sample value that is often the same for every sample (a fit's wavelength, its
/// weights): that one value (stored once), or a `Column`. Indexed like a column
/// (`v[i]`); [`PerSample::from`] a vector keeps one value when every entry has the same
/// bits, so reading it gives exactly the entries given.
#[derive(Debug, Clone, PartialEq)]
pub enum PerSample {
    /// One value shared by every sample.
    One {
        /// The value of every sample.
        value: f64,
        /// Number of samples.
        len: usize,
    },
    /// A value per sample.
    Each(Column),
}

impl PerSample {
    /// Number of samples.
    pub fn len(&self) -> usize {
        match self {
            PerSample::One { len, .. } => *len,
            PerSample::Each(c) => c.len(),
        }
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The values in sample order.
    pub fn iter(&self) -> impl Iterator<Item = f64> + '_ {
        (0..self.len()).map(move |i| self[i])
    }

    /// √v of every sample, in the same form (one value, or a column).
    pub fn sqrt(&self) -> PerSample {
        match self {
            PerSample::One { value, len } => PerSample::One {
                value: value.sqrt(),
                len: *len,
            },
            PerSample::Each(c) => PerSample::Each(c.iter().map(|v| v.sqrt()).collect()),
        }
    }

    /// The median value (`crate::geometry::median`; NaN without samples).
    pub fn median(&self) -> f64 {
        match self {
            PerSample::One { value, len } if *len > 0 => *value,
            PerSample::One { .. } => f64::NAN,
            PerSample::Each(c) => median(c),
        }
    }

    /// The samples `range` (a column's storage is shared).
    pub fn slice(&self, range: std::ops::Range<usize>) -> PerSample {
        match self {
            PerSample::One { value, len } => {
                assert!(
                    range.start <= range.end && range.end <= *len,
                    "slice out of range"
                );
                PerSample::One {
                    value: *value,
                    len: range.len(),
                }
            }
            PerSample::Each(c) => PerSample::Each(c.slice(range)),
        }
    }

    /// The samples at the given indices.
    pub fn subset(&self, idx: &[usize]) -> PerSample {
        match self {
            PerSample::One { value, len } => {
                assert!(idx.iter().all(|&i| i < *len), "subset out of range");
                PerSample::One {
                    value: *value,
                    len: idx.len(),
                }
            }
            PerSample::Each(c) => PerSample::Each(idx.iter().map(|&i| c[i]).collect()),
        }
    }
}

impl From<Vec<f64>> for PerSample {
    fn from(v: Vec<f64>) -> Self {
        match v.first() {
            Some(&first) if v.iter().all(|x| x.to_bits() == first.to_bits()) => PerSample::One {
                value: first,
                len: v.len(),
            },
            _ => PerSample::Each(v.into()),
        }
    }
}

impl FromIterator<f64> for PerSample {
    fn from_iter<I: IntoIterator<Item = f64>>(iter: I) -> Self {
        Vec::from_iter(iter).into()
    }
}

impl std::ops::Index<usize> for PerSample {
    type Output = f64;
    fn index(&self, i: usize) -> &f64 {
        match self {
            PerSample::One { value, len } => {
                assert!(
                    i < *len,
                    "wavelength index {i} out of range for {len} samples"
                );
                value
            }
            PerSample::Each(c) => &c[i],
        }
    }
}

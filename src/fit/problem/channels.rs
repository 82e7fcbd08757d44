//! The channel index of every sample of a fit's data ([`Channels`]).

/// The channel index of every sample: none stored when every sample is in channel 0 (a
/// one-channel fit holds nothing per sample for it). Indexed like a slice (`c[i]`);
/// [`Channels::from`] a vector of zeros stores none.
#[derive(Debug, Clone, PartialEq)]
pub struct Channels {
    each: Option<Vec<usize>>,
    len: usize,
}

impl Channels {
    /// `len` samples, all in channel 0.
    pub fn single(len: usize) -> Self {
        Channels { each: None, len }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether every sample is in channel 0.
    pub fn is_single(&self) -> bool {
        self.each.is_none()
    }

    /// The indices as a slice, None when every sample is in channel 0 (none stored).
    pub fn as_slice(&self) -> Option<&[usize]> {
        self.each.as_deref()
    }

    /// The indices in sample order.
    pub fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.len).map(move |i| self[i])
    }

    /// The samples at the given indices.
    pub fn subset(&self, idx: &[usize]) -> Channels {
        match &self.each {
            None => {
                assert!(idx.iter().all(|&i| i < self.len), "subset out of range");
                Channels::single(idx.len())
            }
            Some(e) => idx.iter().map(|&i| e[i]).collect::<Vec<usize>>().into(),
        }
    }
}

impl From<Vec<usize>> for Channels {
    fn from(v: Vec<usize>) -> Self {
        let len = v.len();
        Channels {
            each: v.iter().any(|&c| c != 0).then_some(v),
            len,
        }
    }
}

impl std::ops::Index<usize> for Channels {
    type Output = usize;
    fn index(&self, i: usize) -> &usize {
        const ZERO: usize = 0;
        match &self.each {
            Some(e) => &e[i],
            None => {
                assert!(
                    i < self.len,
                    "channel index {i} out of range for {}",
                    self.len
                );
                &ZERO
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Channels;

    #[test]
    fn channels_of_one_channel_store_nothing_and_read_zero() {
        let one: Channels = vec![0; 4].into();
        assert!(one.is_single() && one.as_slice().is_none());
        assert_eq!((one[3], one.len()), (0, 4));
        let two: Channels = vec![0, 1, 1, 0].into();
        assert_eq!(two.as_slice(), Some(&[0, 1, 1, 0][..]));
        assert_eq!(two.subset(&[2, 0]).iter().collect::<Vec<_>>(), [1, 0]);
        assert!(
            two.subset(&[0, 3]).is_single(),
            "a subset of channel 0 stores none"
        );
        assert_eq!(Channels::single(3).subset(&[2]), Channels::single(1));
    }
}

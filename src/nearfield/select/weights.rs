//! [`Weights`]: what a selection query returns, up to 4 (camera, weight) pairs summing to 1.

/// Up to 4 (camera index, weight) pairs summing to 1, or none (nothing measured in that direction).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Weights {
    len: u8,
    pairs: [(u32, f64); 4],
}

impl Weights {
    /// No cameras.
    pub const EMPTY: Self = Self {
        len: 0,
        pairs: [(0, 0.0); 4],
    };

    /// The (camera index, weight) pairs.
    pub fn as_slice(&self) -> &[(u32, f64)] {
        &self.pairs[..self.len as usize]
    }

    /// Number of pairs (0…4).
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether no camera was selected.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The pairs, in selection order (Nearest/Idw4: nearest first; Continuous: triangle order).
    pub fn iter(&self) -> std::slice::Iter<'_, (u32, f64)> {
        self.as_slice().iter()
    }

    /// The weight of `camera` (0 when not selected).
    pub fn weight_of(&self, camera: u32) -> f64 {
        self.iter().filter(|p| p.0 == camera).map(|p| p.1).sum()
    }

    pub(super) fn push(&mut self, camera: u32, weight: f64) {
        if let Some(p) = self.pairs.get_mut(self.len as usize) {
            *p = (camera, weight);
            self.len += 1;
        }
    }
}

impl<'a> IntoIterator for &'a Weights {
    type Item = &'a (u32, f64);
    type IntoIter = std::slice::Iter<'a, (u32, f64)>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_accessors() {
        let mut w = Weights::EMPTY;
        assert!(w.is_empty());
        for k in 0..6 {
            w.push(k, 0.25);
        }
        assert_eq!(w.len(), 4);
        assert_eq!(w.weight_of(3), 0.25);
        assert_eq!(w.weight_of(5), 0.0);
        assert_eq!((&w).into_iter().count(), 4);
    }
}

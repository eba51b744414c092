//! Colour maps: a value in 0…1 to an sRGB colour, linear between evenly spaced stops. One home
//! for every false-colour picture: the coverage picture's angle map and colour bar ([`VIRIDIS`]),
//! the isolux diagram's bands between levels ([`YELLOW_ORANGE_BROWN`], one colour per band with
//! [`ColourMap::class`]).

/// A colour map: sRGB stops (8 bits per channel) spread evenly over 0…1, interpolated linearly
/// per channel and rounded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ColourMap {
    /// At least two stops, the colour at 0 first.
    stops: &'static [[u8; 3]],
}

/// The viridis colour map (9 samples, linear in between): perceptually uniform, dark violet at 0
/// to yellow at 1.
pub const VIRIDIS: ColourMap = ColourMap {
    stops: &[
        [68, 1, 84],
        [71, 44, 122],
        [59, 81, 139],
        [44, 113, 142],
        [33, 144, 141],
        [39, 173, 129],
        [92, 200, 99],
        [170, 220, 50],
        [253, 231, 37],
    ],
};

/// A light yellow-orange-brown ramp, so dark lines and white labels drawn over it stay readable
/// at every value.
pub const YELLOW_ORANGE_BROWN: ColourMap = ColourMap {
    stops: &[
        [255, 250, 210],
        [254, 232, 150],
        [254, 203, 95],
        [253, 163, 64],
        [238, 118, 42],
        [205, 82, 28],
    ],
};

impl ColourMap {
    /// The stops, the colour at 0 first, the colour at 1 last.
    pub fn stops(&self) -> &'static [[u8; 3]] {
        self.stops
    }

    /// The colour at `t`, clamped to 0…1 (the colour at 0 for a non-finite `t`).
    pub fn at(&self, t: f64) -> [u8; 3] {
        let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
        let last = self.stops.len() - 1;
        let x = t * last as f64;
        let i = (x.floor() as usize).min(last - 1);
        let f = x - i as f64;
        let mut out = [0u8; 3];
        for (k, o) in out.iter_mut().enumerate() {
            let (a, b) = (f64::from(self.stops[i][k]), f64::from(self.stops[i + 1][k]));
            *o = (a + (b - a) * f).round().clamp(0.0, 255.0) as u8;
        }
        out
    }

    /// The colour of class `i` of `n` (i < n), the classes spread evenly from the colour at 0
    /// (class 0) to the colour at 1 (class n − 1); a single class gets the colour at 0.
    pub fn class(&self, i: usize, n: usize) -> [u8; 3] {
        self.at(if n <= 1 { 0.0 } else { i as f64 / (n - 1) as f64 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_middle() {
        assert_eq!(VIRIDIS.at(0.0), [68, 1, 84]);
        assert_eq!(VIRIDIS.at(1.0), [253, 231, 37]);
        assert_eq!(VIRIDIS.at(f64::NAN), [68, 1, 84]);
        assert_eq!(VIRIDIS.at(7.0), [253, 231, 37]);
        assert_eq!(VIRIDIS.at(0.5), [33, 144, 141]);
        // Halfway between the first two stops.
        assert_eq!(VIRIDIS.at(1.0 / 16.0), [70, 23, 103]);
    }

    #[test]
    fn classes_span_the_map() {
        let m = YELLOW_ORANGE_BROWN;
        assert_eq!(m.class(0, 6), m.stops()[0]);
        assert_eq!(m.class(5, 6), m.stops()[5]);
        assert_eq!(m.class(0, 1), m.stops()[0]);
        assert_eq!(m.class(1, 3), [254, 183, 80]);
    }
}

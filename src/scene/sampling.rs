//! Random numbers and the sampling of directions for the reference path tracer.
//!
//! Promises:
//! - [`Pcg32`] is PCG-XSH-RR 64/32 (O'Neill 2014): a 64-bit LCG state, 32-bit output, one stream
//!   per seed pair. Streams are derived from (seed, point index) by SplitMix64, so a result
//!   depends on the seed and the point, never on thread scheduling.
//! - [`Pcg32::next_f64`] is uniform in [0, 1) with 53 random bits.
//! - [`cosine_hemisphere`] returns unit directions about a unit normal with density cos θ / π
//!   (Malley's method: a uniform point on the unit disc lifted to the hemisphere).

use glam::DVec3;

/// SplitMix64's finaliser (Steele, Lea, Flood 2014): a 64-bit mixing function.
pub fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// PCG-XSH-RR 64/32.
#[derive(Debug, Clone)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MULT: u64 = 6_364_136_223_846_793_005;

    /// A generator on stream `stream` from `seed`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut g = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        g.next_u32();
        g.state = g.state.wrapping_add(seed);
        g.next_u32();
        g
    }

    /// The generator for point `index` of a run seeded with `seed`.
    pub fn for_point(seed: u64, index: u64) -> Self {
        let a = splitmix64(seed ^ splitmix64(index));
        let b = splitmix64(a ^ index.rotate_left(32));
        Pcg32::new(a, b)
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        let hi = u64::from(self.next_u32()) << 21;
        let lo = u64::from(self.next_u32()) >> 11;
        (hi | lo) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// Two unit vectors completing the unit normal `n` to a right-handed orthonormal basis (Duff et
/// al. 2017, "Building an Orthonormal Basis, Revisited").
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A unit direction about the unit normal `n` with density cos θ / π, from two uniform numbers.
pub fn cosine_hemisphere(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let phi = std::f64::consts::TAU * u2;
    let (x, y) = (r * phi.cos(), r * phi.sin());
    let z = (1.0 - u1).max(0.0).sqrt();
    let (t, b) = basis(n);
    (t * x + b * y + n * z).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg_matches_the_reference_sequence() {
        // pcg32-demo (pcg-c-basic) seeded with initstate 42, initseq 54: the first outputs.
        let mut g = Pcg32::new(42, 54);
        let want = [
            0xa15c02b7u32,
            0x7b47f409,
            0xba1d3330,
            0x83d2f293,
            0xbfa4784b,
            0xcbed606e,
        ];
        for w in want {
            assert_eq!(g.next_u32(), w);
        }
        let mut g = Pcg32::for_point(7, 3);
        let x: Vec<f64> = (0..1000).map(|_| g.next_f64()).collect();
        assert!(x.iter().all(|v| (0.0..1.0).contains(v)));
        let mean = x.iter().sum::<f64>() / 1000.0;
        assert!((mean - 0.5).abs() < 0.03, "{mean}");
        assert_ne!(Pcg32::for_point(7, 3).next_u32(), Pcg32::for_point(7, 4).next_u32());
    }

    #[test]
    fn cosine_samples_have_the_cosine_moments() {
        // E[cos θ] = 2/3 and E[cos² θ] = 1/2 under density cos θ / π; unit length; upper side.
        let mut g = Pcg32::new(1, 2);
        for n in [
            DVec3::Z,
            DVec3::NEG_Z,
            DVec3::new(0.6, -0.8, 0.0),
            DVec3::new(1.0, 2.0, -2.0) / 3.0,
        ] {
            let (t, b) = basis(n);
            assert!(t.dot(n).abs() < 1e-12 && b.dot(n).abs() < 1e-12 && t.dot(b).abs() < 1e-12);
            assert!((t.cross(b) - n).length() < 1e-12, "right-handed");
            let (mut m1, mut m2) = (0.0, 0.0);
            let k = 20_000;
            for _ in 0..k {
                let d = cosine_hemisphere(n, g.next_f64(), g.next_f64());
                assert!((d.length() - 1.0).abs() < 1e-12);
                let c = d.dot(n);
                assert!(c >= 0.0);
                m1 += c;
                m2 += c * c;
            }
            assert!((m1 / k as f64 - 2.0 / 3.0).abs() < 0.01, "{}", m1 / k as f64);
            assert!((m2 / k as f64 - 0.5).abs() < 0.01, "{}", m2 / k as f64);
        }
    }
}

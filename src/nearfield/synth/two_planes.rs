//! Two emitting planes at different depths: a front plane of opaque emitting tiles with gaps and a
//! striped back plane behind it, seen through the gaps. Intensity and flux are exact: shifted
//! rectangle overlaps for I(ω), configuration factors of parallel rectangles for Φ.

use std::f64::consts::PI;

use glam::DVec3;

use super::luminaires::{cos_below, hit_from_below, rect_bounds, Rect};
use super::proxy::ProxyMesh;
use super::{unit, Aabb, Luminaire};

/// A·F₁→₂ (m²) between two parallel, axis-aligned rectangles `a` and `b` in planes `z` apart: the
/// fraction of a Lambertian emitter's flux on `a` that reaches `b`, times a's area. Closed form for
/// parallel rectangles of arbitrary offset (after Howell's catalogue of configuration factors, C-13;
/// normalised here so that coaxial unit squares one unit apart give F = 0.19982, and checked against
/// brute-force integration of z²/(π r⁴) in the tests):
/// A₁F₁₂ = 1/π Σ (−1)^(i+j+k+l) G(x_i − ξ_k, y_j − η_l) with
/// G(u, v) = ½ v √(u²+z²) atan(v/√(u²+z²)) + ½ u √(v²+z²) atan(u/√(v²+z²)) − ¼ z² ln(u²+v²+z²).
pub(crate) fn parallel_exchange_area(a: &Rect, b: &Rect, z: f64) -> f64 {
    let g = |u: f64, v: f64| -> f64 {
        let su = (u * u + z * z).sqrt();
        let sv = (v * v + z * z).sqrt();
        let mut r = -0.25 * z * z * (u * u + v * v + z * z).ln();
        if su > 0.0 {
            r += 0.5 * v * su * (v / su).atan();
        }
        if sv > 0.0 {
            r += 0.5 * u * sv * (u / sv).atan();
        }
        r
    };
    let xs = [a.x0, a.x1];
    let ys = [a.y0, a.y1];
    let xis = [b.x0, b.x1];
    let etas = [b.y0, b.y1];
    let mut sum = 0.0;
    for (i, x) in xs.iter().enumerate() {
        for (j, y) in ys.iter().enumerate() {
            for (k, xi) in xis.iter().enumerate() {
                for (l, eta) in etas.iter().enumerate() {
                    let sign = if (i + j + k + l) % 2 == 0 { 1.0 } else { -1.0 };
                    sum += sign * g(x - xi, y - eta);
                }
            }
        }
    }
    sum / PI
}

/// Two emitting planes at different depths: a front plane of opaque emitting tiles with gaps, and a
/// striped back plane behind it, seen through the gaps (parallax: the back plane shifts by
/// depth·tan γ against the tiles).
#[derive(Debug, Clone, PartialEq)]
pub struct TwoPlanes {
    tiles_per_side: usize,
    tile_m: f64,
    pitch_m: f64,
    l_tile_even: f64,
    l_tile_odd: f64,
    back: Rect,
    depth_m: f64,
    stripe_m: f64,
    l_stripe_even: f64,
    l_stripe_odd: f64,
}

impl TwoPlanes {
    /// `two-planes`: front plane z = 0: 5 × 5 square tiles of 30 mm at a 40 mm pitch (10 mm gaps),
    /// centred, a checkerboard of 3,000 cd/m² (i + j even) and 1,200 cd/m² (odd); back plane
    /// z = +0.05 m (50 mm behind): 200 × 200 mm, stripes 20 mm wide across X (constant along Y),
    /// 6,000 cd/m² (even stripes, counted from x = −100 mm) and 2,000 cd/m² (odd). Both face down.
    pub fn standard() -> Self {
        Self {
            tiles_per_side: 5,
            tile_m: 0.03,
            pitch_m: 0.04,
            l_tile_even: 3_000.0,
            l_tile_odd: 1_200.0,
            back: Rect::centred(0.0, 0.0, 0.2, 0.2),
            depth_m: 0.05,
            stripe_m: 0.02,
            l_stripe_even: 6_000.0,
            l_stripe_odd: 2_000.0,
        }
    }

    fn tile_offset(&self) -> f64 {
        0.5 * (self.tiles_per_side as f64 - 1.0)
    }

    /// Tile (i, j) and its luminance.
    fn tiles(&self) -> impl Iterator<Item = (Rect, f64)> + '_ {
        let n = self.tiles_per_side;
        (0..n).flat_map(move |j| {
            (0..n).map(move |i| {
                let cx = (i as f64 - self.tile_offset()) * self.pitch_m;
                let cy = (j as f64 - self.tile_offset()) * self.pitch_m;
                let l = if (i + j) % 2 == 0 {
                    self.l_tile_even
                } else {
                    self.l_tile_odd
                };
                (Rect::centred(cx, cy, self.tile_m, self.tile_m), l)
            })
        })
    }

    /// Luminance of the front plane at (x, y), `None` in a gap (transparent).
    fn front_at(&self, x: f64, y: f64) -> Option<f64> {
        let n = self.tiles_per_side as i64;
        let idx = |v: f64| -> Option<i64> {
            let i = (v / self.pitch_m + self.tile_offset()).round();
            if !(i >= 0.0 && i < n as f64) {
                return None;
            }
            let c = (i - self.tile_offset()) * self.pitch_m;
            (v >= c - 0.5 * self.tile_m && v < c + 0.5 * self.tile_m).then_some(i as i64)
        };
        let (i, j) = (idx(x)?, idx(y)?);
        Some(if (i + j) % 2 == 0 {
            self.l_tile_even
        } else {
            self.l_tile_odd
        })
    }

    /// Stripes of the back plane: (x0, x1, L).
    fn stripes(&self) -> impl Iterator<Item = (f64, f64, f64)> + '_ {
        let n = ((self.back.x1 - self.back.x0) / self.stripe_m).round() as usize;
        (0..n).map(move |k| {
            let x0 = self.back.x0 + k as f64 * self.stripe_m;
            let l = if k % 2 == 0 {
                self.l_stripe_even
            } else {
                self.l_stripe_odd
            };
            (x0, (x0 + self.stripe_m).min(self.back.x1), l)
        })
    }

    /// Luminance of the back plane at (x, y); 0 outside it.
    fn back_at(&self, x: f64, y: f64) -> f64 {
        if !self.back.contains(x, y) {
            return 0.0;
        }
        let k = ((x - self.back.x0) / self.stripe_m).floor() as i64;
        if k % 2 == 0 {
            self.l_stripe_even
        } else {
            self.l_stripe_odd
        }
    }

    /// ∫ L_back dA over `r` ∩ back plane.
    fn back_integral(&self, r: &Rect) -> f64 {
        let Some(r) = r.intersect(&self.back) else {
            return 0.0;
        };
        let h = r.y1 - r.y0;
        self.stripes()
            .map(|(a, b, l)| l * (b.min(r.x1) - a.max(r.x0)).max(0.0))
            .sum::<f64>()
            * h
    }
}

impl Luminaire for TwoPlanes {
    fn name(&self) -> &str {
        "two-planes"
    }
    fn description(&self) -> String {
        "front plane z = 0: 5 × 5 tiles of 30 mm at 40 mm pitch, checkerboard 3,000/1,200 cd/m²; back \
         plane 50 mm behind: 200 × 200 mm, 20 mm stripes 6,000/2,000 cd/m², seen through the 10 mm gaps"
            .into()
    }
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        if let Some((x, y)) = hit_from_below(origin, dir, 0.0) {
            if let Some(l) = self.front_at(x, y) {
                return l;
            }
        }
        hit_from_below(origin, dir, self.depth_m).map_or(0.0, |(x, y)| self.back_at(x, y))
    }
    fn intensity_cd(&self, dir: DVec3) -> f64 {
        let Some(u) = unit(dir) else { return 0.0 };
        let Some(c) = cos_below(u) else { return 0.0 };
        // A back-plane point p is hidden where p + depth·ω_xy/(−ω_z) lies in a tile, i.e. p in the
        // tile shifted by s = depth·ω_xy/ω_z. Tiles are disjoint, so their shadows are too.
        let (sx, sy) = (self.depth_m * u.x / u.z, self.depth_m * u.y / u.z);
        let mut sum = 0.0;
        for (t, l) in self.tiles() {
            sum += l * t.area();
            sum -= self.back_integral(&t.shifted(sx, sy));
        }
        sum += self.back_integral(&self.back);
        c * sum
    }
    fn flux_lm(&self) -> f64 {
        let front: f64 = self.tiles().map(|(t, l)| l * t.area()).sum();
        let mut back = 0.0;
        for (x0, x1, l) in self.stripes() {
            let s = Rect {
                x0,
                x1,
                y0: self.back.y0,
                y1: self.back.y1,
            };
            let blocked: f64 = self
                .tiles()
                .map(|(t, _)| parallel_exchange_area(&s, &t, self.depth_m))
                .sum();
            back += l * (s.area() - blocked);
        }
        PI * (front + back)
    }
    fn bounds(&self) -> Aabb {
        let front = self.tiles().fold(self.back, |acc, (t, _)| Rect {
            x0: acc.x0.min(t.x0),
            x1: acc.x1.max(t.x1),
            y0: acc.y0.min(t.y0),
            y1: acc.y1.max(t.y1),
        });
        rect_bounds(&front, 0.0, self.depth_m)
    }
    fn max_luminance(&self) -> f64 {
        self.l_tile_even
            .max(self.l_tile_odd)
            .max(self.l_stripe_even)
            .max(self.l_stripe_odd)
    }
    fn proxy(&self) -> ProxyMesh {
        let mut m = ProxyMesh::new(self.name());
        for (k, (t, _)) in self.tiles().enumerate() {
            m.add_rect(&format!("front tile {k}"), t.x0, t.x1, t.y0, t.y1, 0.0);
        }
        let b = self.back;
        m.add_rect("back plane", b.x0, b.x1, b.y0, b.y1, self.depth_m);
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute-force A·F between parallel rectangles (midpoint rule on both).
    fn brute_exchange(a: &Rect, b: &Rect, z: f64, n: usize) -> f64 {
        let mut s = 0.0;
        let (da, db) = (a.area() / (n * n) as f64, b.area() / (n * n) as f64);
        for i in 0..n {
            for j in 0..n {
                let x = a.x0 + (i as f64 + 0.5) / n as f64 * (a.x1 - a.x0);
                let y = a.y0 + (j as f64 + 0.5) / n as f64 * (a.y1 - a.y0);
                for k in 0..n {
                    for l in 0..n {
                        let u = b.x0 + (k as f64 + 0.5) / n as f64 * (b.x1 - b.x0);
                        let v = b.y0 + (l as f64 + 0.5) / n as f64 * (b.y1 - b.y0);
                        let r2 = (x - u).powi(2) + (y - v).powi(2) + z * z;
                        s += z * z / (PI * r2 * r2) * da * db;
                    }
                }
            }
        }
        s
    }

    #[test]
    fn view_factor_of_parallel_rectangles() {
        // Coaxial unit squares one unit apart: F = 0.19982 (tabulated).
        let sq = Rect::centred(0.0, 0.0, 1.0, 1.0);
        let f = parallel_exchange_area(&sq, &sq, 1.0);
        assert!((f - 0.19982).abs() < 1e-4, "{f}");
        // Offset rectangles against brute force.
        let a = Rect::centred(-0.03, 0.01, 0.02, 0.2);
        let b = Rect::centred(0.02, -0.04, 0.03, 0.03);
        let exact = parallel_exchange_area(&a, &b, 0.05);
        let brute = brute_exchange(&a, &b, 0.05, 24);
        assert!(((exact - brute) / exact).abs() < 1e-3, "{exact} vs {brute}");
        // Reciprocity.
        let ba = parallel_exchange_area(&b, &a, 0.05);
        assert!(((exact - ba) / exact).abs() < 1e-9);
    }

    #[test]
    fn two_planes_gaps_show_the_back_plane() {
        let t = TwoPlanes::standard();
        let up = DVec3::Z;
        // Centre tile (i = j = 2: even → 3,000).
        assert_eq!(t.radiance(DVec3::new(0.0, 0.0, -1.0), up), 3000.0);
        // Gap at x = 21 mm (between tiles), y = 0: back stripe k = floor((0.021 + 0.1)/0.02) = 6 → 6,000.
        assert_eq!(t.radiance(DVec3::new(0.021, 0.0, -1.0), up), 6000.0);
        // x = 41 mm is a gap in y (y = 20 mm): back stripe k = 7 → 2,000.
        assert_eq!(t.radiance(DVec3::new(0.041, 0.02, -1.0), up), 2000.0);
        // Seen at normal incidence the back plane contributes its gaps only.
        let i0 = t.intensity_cd(-DVec3::Z);
        let tiles: f64 = t.tiles().map(|(r, l)| r.area() * l).sum();
        let back_total = t.back_integral(&t.back);
        let hidden: f64 = t.tiles().map(|(r, _)| t.back_integral(&r)).sum();
        assert!((i0 - (tiles + back_total - hidden)).abs() < 1e-9);
    }
}

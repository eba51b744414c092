//! The (φ, θ) cell grid: cell of a direction, the cap that covers each cell, and the cells a cap may
//! touch (a conservative enumeration through the cap's φ/θ range).

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::spherical::{angle, from_phi_theta, phi_theta};

/// Fewest θ rows of the grid.
pub const MIN_THETA_CELLS: u32 = 4;
/// Most θ rows of the grid (φ has twice as many columns).
pub const MAX_THETA_CELLS: u32 = 2048;

/// The fp32 margin added to a cap of radius `r` that covers a cell: 0.01 r + 2·10⁻⁵ rad.
fn margin(r: f64) -> f64 {
    0.01 * r + 2e-5
}

/// The largest angle from the centre of the (φ, θ) rectangle [p0, p1] × [t0, t1] to its points: a
/// corner or an edge midpoint (along a parallel the distance grows towards the corners; along a meridian
/// it has no interior maximum).
fn rect_radius(centre: DVec3, p0: f64, p1: f64, t0: f64, t1: f64) -> f64 {
    let (pc, tc) = (0.5 * (p0 + p1), 0.5 * (t0 + t1));
    [
        (p0, t0),
        (p1, t0),
        (p0, t1),
        (p1, t1),
        (pc, t0),
        (pc, t1),
        (p0, tc),
        (p1, tc),
    ]
    .iter()
    .map(|&(p, t)| angle(centre, from_phi_theta(p, t)))
    .fold(0.0, f64::max)
}

/// A regular grid over (φ, θ): `n_phi = 2 · n_theta` columns of φ ∈ [0, 2π), `n_theta` rows of
/// θ ∈ [0, π] (θ from +Z). Cell index = j · n_phi + i.
#[derive(Debug, Clone)]
pub(super) struct CellGrid {
    /// Columns (φ).
    pub n_phi: u32,
    /// Rows (θ).
    pub n_theta: u32,
    /// Cap radius of each row's cells (rad), margins included.
    rho: Vec<f64>,
    /// (sin, cos) of each row's centre θ.
    row_sc: Vec<(f64, f64)>,
    /// (sin, cos) of each column's centre φ.
    col_sc: Vec<(f64, f64)>,
}

impl CellGrid {
    /// The grid for cells of about `cell_deg` degrees: n_theta = clamp(ceil(180 / cell_deg), 4, 2048).
    pub fn for_cell_deg(cell_deg: f64) -> Self {
        let n = (180.0 / cell_deg).ceil();
        let n_theta = if n.is_finite() {
            n.clamp(f64::from(MIN_THETA_CELLS), f64::from(MAX_THETA_CELLS)) as u32
        } else {
            MAX_THETA_CELLS
        };
        Self::new(n_theta)
    }

    /// The grid of `n_theta` rows (clamped to 4…2048) and 2 · n_theta columns.
    pub fn new(n_theta: u32) -> Self {
        let n_theta = n_theta.clamp(MIN_THETA_CELLS, MAX_THETA_CELLS);
        let n_phi = 2 * n_theta;
        let dphi = TAU / f64::from(n_phi);
        let dtheta = PI / f64::from(n_theta);
        let col_sc = (0..n_phi).map(|i| ((f64::from(i) + 0.5) * dphi).sin_cos()).collect();
        let mut row_sc = Vec::with_capacity(n_theta as usize);
        let mut rho = Vec::with_capacity(n_theta as usize);
        for j in 0..n_theta {
            let (t0, t1) = (f64::from(j) * dtheta, f64::from(j + 1) * dtheta);
            let tc = 0.5 * (t0 + t1);
            row_sc.push(tc.sin_cos());
            // By symmetry in φ, the cap of the column-0 cell serves the whole row. The farthest point of
            // a (φ, θ) rectangle from its centre is a corner; the edge midpoints are taken too.
            let r = rect_radius(from_phi_theta(0.5 * dphi, tc), 0.0, dphi, t0, t1);
            rho.push(r + margin(r));
        }
        Self {
            n_phi,
            n_theta,
            rho,
            row_sc,
            col_sc,
        }
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.n_phi as usize * self.n_theta as usize
    }

    /// The cell of a unit vector: φ = atan2(y, x) (+ 2π if < 0), θ = acos(clamp(z, −1, 1)),
    /// i = min(floor(φ / 2π · n_phi), n_phi − 1), j = min(floor(θ / π · n_theta), n_theta − 1),
    /// index j · n_phi + i. A non-finite vector lands in cell 0 (float-to-int casts saturate).
    pub fn cell_of(&self, u: DVec3) -> usize {
        let (phi, theta) = phi_theta(u);
        let i = ((phi / TAU * f64::from(self.n_phi)).floor() as u32).min(self.n_phi - 1);
        let j = ((theta / PI * f64::from(self.n_theta)).floor() as u32).min(self.n_theta - 1);
        j as usize * self.n_phi as usize + i as usize
    }

    /// The centre of cell `cell` (unit vector at the cell's centre φ and θ).
    pub fn centre(&self, cell: usize) -> DVec3 {
        let (i, j) = (cell % self.n_phi as usize, cell / self.n_phi as usize);
        let (sp, cp) = self.col_sc[i];
        let (st, ct) = self.row_sc[j];
        DVec3::new(st * cp, st * sp, ct)
    }

    /// The radius (rad) of the cap around [`Self::centre`] that covers cell `cell`, with margins for a
    /// GPU that computes the cell in fp32: 1.01 · (farthest corner or edge midpoint) + 2·10⁻⁵.
    pub fn rho(&self, cell: usize) -> f64 {
        self.rho[cell / self.n_phi as usize]
    }

    /// Caps (centre, radius) whose union covers every point within the fp32 margin of cell `cell`
    /// (the margin of its cap, [`Self::rho`]): the cell split into about square pieces, each covered as a
    /// cell is, plus that margin. Tighter than the cell's one cap where cells are long and thin (near
    /// the poles).
    pub fn cover(&self, cell: usize) -> Vec<(DVec3, f64)> {
        let (i, j) = (cell % self.n_phi as usize, cell / self.n_phi as usize);
        let dphi = TAU / f64::from(self.n_phi);
        let dtheta = PI / f64::from(self.n_theta);
        let (p0, t0) = (i as f64 * dphi, j as f64 * dtheta);
        let (p1, t1) = (p0 + dphi, t0 + dtheta);
        let raw = rect_radius(self.centre(cell), p0, p1, t0, t1);
        let m = self.rho(cell) - raw;
        // Pieces: 3 along θ; along φ as many as keep them about square (1…12).
        let width = dphi * t0.sin().max(t1.sin());
        let (nt, np) = (3usize, ((3.0 * width / dtheta).round() as usize).clamp(1, 12));
        let mut out = Vec::with_capacity(nt * np);
        for a in 0..np {
            let (q0, q1) = (p0 + dphi * a as f64 / np as f64, p0 + dphi * (a + 1) as f64 / np as f64);
            for b in 0..nt {
                let (s0, s1) = (
                    t0 + dtheta * b as f64 / nt as f64,
                    t0 + dtheta * (b + 1) as f64 / nt as f64,
                );
                let c = from_phi_theta(0.5 * (q0 + q1), 0.5 * (s0 + s1));
                out.push((c, rect_radius(c, q0, q1, s0, s1) + m));
            }
        }
        out
    }

    /// The largest cell cap radius.
    pub fn rho_max(&self) -> f64 {
        self.rho.iter().copied().fold(0.0, f64::max)
    }

    /// Calls `f` with every cell whose (φ, θ) rectangle may hold a point within `r` of the unit vector
    /// `centre` (a superset): the rows of θ ∈ [θc − r, θc + r]; all columns when that range reaches a
    /// pole, else φ ∈ φc ± asin(min(1, sin r / sin θc)), wrapped.
    pub fn for_each_cell_near(&self, centre: DVec3, r: f64, mut f: impl FnMut(usize)) {
        let r = r + 1e-9;
        let (phi, theta) = phi_theta(centre);
        let (np, nt) = (i64::from(self.n_phi), i64::from(self.n_theta));
        let row = |t: f64| ((t / PI * nt as f64).floor() as i64).clamp(0, nt - 1);
        let (j0, j1) = (row(theta - r), row(theta + r));
        let all_phi = r >= PI || theta - r <= 0.0 || theta + r >= PI;
        let (i0, i1) = if all_phi {
            (0, np - 1)
        } else {
            let dphi = (r.sin() / theta.sin()).min(1.0).asin() + 1e-9;
            let a = ((phi - dphi) / TAU * np as f64).floor() as i64;
            let b = ((phi + dphi) / TAU * np as f64).floor() as i64;
            if b - a + 1 >= np {
                (0, np - 1)
            } else {
                (a, b)
            }
        };
        for j in j0..=j1 {
            let base = j as usize * self.n_phi as usize;
            for k in i0..=i1 {
                f(base + k.rem_euclid(np) as usize);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::nearfield::layout::SplitMix64;

    fn random_unit(rng: &mut SplitMix64) -> DVec3 {
        let z = 2.0 * rng.next_f64() - 1.0;
        let a = TAU * rng.next_f64();
        let s = (1.0 - z * z).sqrt();
        DVec3::new(s * a.cos(), s * a.sin(), z)
    }

    #[test]
    fn grid_size_follows_the_cell_size() {
        assert_eq!(CellGrid::for_cell_deg(1.0).n_theta, 180);
        assert_eq!(CellGrid::for_cell_deg(0.7).n_theta, 258);
        assert_eq!(CellGrid::for_cell_deg(90.0).n_theta, 4);
        assert_eq!(CellGrid::for_cell_deg(1e-6).n_theta, 2048);
        let g = CellGrid::for_cell_deg(2.0);
        assert_eq!((g.n_phi, g.n_theta, g.cells()), (180, 90, 16_200));
    }

    #[test]
    fn cell_of_follows_the_formula_and_its_cap_covers_the_point() {
        let g = CellGrid::new(37);
        let mut rng = SplitMix64::new(3);
        for _ in 0..20_000 {
            let u = random_unit(&mut rng);
            let c = g.cell_of(u);
            assert!(c < g.cells());
            assert!(angle(u, g.centre(c)) <= g.rho(c), "{u}");
        }
        // Poles and the φ wrap.
        assert_eq!(g.cell_of(DVec3::Z), 0);
        assert_eq!(g.cell_of(-DVec3::Z) / g.n_phi as usize, 36);
        assert_eq!(
            g.cell_of(DVec3::new(1.0, -1e-300, 0.0)) % g.n_phi as usize,
            g.n_phi as usize - 1
        );
        assert_eq!(g.cell_of(DVec3::NAN), 0);
        // Known cell: φ = 10°, θ = 100° with 74 × 37 cells of 360/74° and 180/37°.
        let u = from_phi_theta(10f64.to_radians(), 100f64.to_radians());
        assert_eq!(g.cell_of(u), 20 * 74 + 2);
    }

    #[test]
    fn cell_cover_covers_the_cell_and_its_margin() {
        for g in [CellGrid::new(4), CellGrid::new(37), CellGrid::new(330)] {
            let mut rng = SplitMix64::new(u64::from(g.n_theta));
            for k in 0..20_000 {
                // Near the poles half of the time.
                let mut u = random_unit(&mut rng);
                if k % 2 == 0 {
                    u = (u * DVec3::new(0.02, 0.02, 1.0)).normalize();
                }
                let cell = g.cell_of(u);
                let cover = g.cover(cell);
                assert!(cover.len() >= 3 && cover.len() <= 36);
                // A point of the cell, and one up to 1.9·10⁻⁵ rad outside it (within the margin).
                let t = u.cross(random_unit(&mut rng)).normalize();
                let x = (u + t * 1.9e-5 * rng.next_f64()).normalize();
                for p in [u, x] {
                    assert!(
                        cover.iter().any(|&(c, r)| angle(p, c) <= r),
                        "cell {cell} of {} rows: {p} uncovered",
                        g.n_theta
                    );
                }
            }
        }
    }

    #[test]
    fn cap_enumeration_is_a_superset() {
        let g = CellGrid::new(45);
        let mut rng = SplitMix64::new(9);
        for k in 0..300 {
            let c = random_unit(&mut rng);
            let r = [0.01, 0.1, 0.5, 1.5, 3.0][k % 5];
            let mut hit = vec![false; g.cells()];
            g.for_each_cell_near(c, r, |i| hit[i] = true);
            for _ in 0..200 {
                // A random point within r of c.
                let p = random_unit(&mut rng);
                let axis = c.cross(p).normalize_or_zero();
                if axis == DVec3::ZERO {
                    continue;
                }
                let a = r * rng.next_f64().sqrt();
                let q = c * a.cos() + axis.cross(c) * a.sin();
                assert!(hit[g.cell_of(q)], "c {c} r {r} q {q}");
            }
        }
    }
}

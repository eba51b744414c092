//! Nearest unit vector among a fixed set (a ray's camera) and the solid angles of the set's spherical
//! Voronoi cells (each camera's share of the sphere of directions), exact or sampled.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Nearest unit vector among a fixed set, by great-circle angle, in about O(1) per query: the unit
/// vectors are bucketed in a uniform grid over the cube [−1, 1]³ and searched shell by shell around
/// the query's cell until no unvisited cell can hold a closer one.
#[derive(Debug, Clone)]
pub struct NearestDirection {
    dirs: Vec<DVec3>,
    merged: Vec<bool>,
    grid: usize,
    cell: f64,
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl NearestDirection {
    /// Buckets `dirs` (normalised here; zero vectors are never returned). Directions closer than
    /// [`NearestDirection::MERGE_CHORD`] to an earlier one (e.g. the meridian starts at a pole, equal
    /// up to rounding) are merged into it: only the lowest index of such a group is ever returned.
    pub fn new(dirs: &[DVec3]) -> Self {
        let dirs: Vec<DVec3> = dirs.iter().map(|d| d.normalize_or_zero()).collect();
        // About one direction per occupied cell: the sphere crosses ~4π/h² cells of size h = 2/g.
        let grid = ((dirs.len() as f64 / 2.0).sqrt().ceil() as usize).clamp(1, 128);
        let cell = 2.0 / grid as f64;
        let mut me = Self {
            merged: dirs.iter().map(|d| *d == DVec3::ZERO).collect(),
            dirs,
            grid,
            cell,
            starts: Vec::new(),
            items: Vec::new(),
        };
        me.bucket();
        let mut near = Vec::new();
        let mut any = false;
        for i in 0..me.dirs.len() {
            if me.merged[i] {
                continue;
            }
            near.clear();
            let c = me.coords(me.dirs[i]);
            me.shell(c, 0, &mut near);
            me.shell(c, 1, &mut near);
            let di = me.dirs[i];
            if near
                .iter()
                .any(|&j| j < i && !me.merged[j] && (me.dirs[j] - di).length() < Self::MERGE_CHORD)
            {
                me.merged[i] = true;
                any = true;
            }
        }
        if any {
            me.bucket();
        }
        me
    }

    /// Chord distance below which two directions count as one (10⁻⁹, about 6·10⁻⁸ degrees).
    pub const MERGE_CHORD: f64 = 1e-9;

    /// (Re)builds the buckets from the directions not merged away.
    fn bucket(&mut self) {
        let cells = self.grid * self.grid * self.grid;
        let mut counts = vec![0u32; cells + 1];
        let keys: Vec<Option<usize>> = (0..self.dirs.len())
            .map(|i| (!self.merged[i]).then(|| self.key(self.coords(self.dirs[i]))))
            .collect();
        for k in keys.iter().flatten() {
            counts[*k + 1] += 1;
        }
        for i in 0..cells {
            counts[i + 1] += counts[i];
        }
        let mut fill = counts.clone();
        let mut items = vec![0u32; counts[cells] as usize];
        for (i, k) in keys.iter().enumerate() {
            if let Some(k) = k {
                items[fill[*k] as usize] = i as u32;
                fill[*k] += 1;
            }
        }
        self.starts = counts;
        self.items = items;
    }

    /// Whether direction `i` was merged into an earlier one (or is zero) and is never returned.
    pub fn is_merged(&self, i: usize) -> bool {
        self.merged.get(i).copied().unwrap_or(true)
    }

    fn coords(&self, d: DVec3) -> [usize; 3] {
        let c = |v: f64| (((v + 1.0) / self.cell).floor().max(0.0) as usize).min(self.grid - 1);
        [c(d.x), c(d.y), c(d.z)]
    }

    fn key(&self, [x, y, z]: [usize; 3]) -> usize {
        (z * self.grid + y) * self.grid + x
    }

    /// Number of directions.
    pub fn len(&self) -> usize {
        self.dirs.len()
    }

    /// Whether there are no directions.
    pub fn is_empty(&self) -> bool {
        self.dirs.is_empty()
    }

    /// The (normalised) direction `i`.
    pub fn direction(&self, i: usize) -> Option<DVec3> {
        self.dirs.get(i).copied()
    }

    /// Index of the direction nearest to `k` (unit), ties to the lower index; `None` when empty or
    /// `k` is not finite.
    pub fn nearest(&self, k: DVec3) -> Option<usize> {
        if !k.is_finite() || self.items.is_empty() {
            return None;
        }
        let c = self.coords(k);
        let g = self.grid as isize;
        let mut best: Option<(f64, usize)> = None;
        for r in 0..g {
            for dz in -r..=r {
                for dy in -r..=r {
                    for dx in -r..=r {
                        if dx.abs().max(dy.abs()).max(dz.abs()) != r {
                            continue;
                        }
                        let (x, y, z) = (c[0] as isize + dx, c[1] as isize + dy, c[2] as isize + dz);
                        if x < 0 || y < 0 || z < 0 || x >= g || y >= g || z >= g {
                            continue;
                        }
                        let key = self.key([x as usize, y as usize, z as usize]);
                        let (s, e) = (self.starts[key] as usize, self.starts[key + 1] as usize);
                        for &i in &self.items[s..e] {
                            let i = i as usize;
                            let d2 = (self.dirs[i] - k).length_squared();
                            if best.is_none_or(|(b, bi)| d2 < b || (d2 == b && i < bi)) {
                                best = Some((d2, i));
                            }
                        }
                    }
                }
            }
            // Any direction not yet visited is at least r cells (r·h) away from k.
            if let Some((b, _)) = best {
                let reach = r as f64 * self.cell;
                if b <= reach * reach {
                    break;
                }
            }
        }
        best.map(|(_, i)| i)
    }

    /// Generators in the cells at Chebyshev distance exactly `r` from cell `c`.
    fn shell(&self, c: [usize; 3], r: isize, out: &mut Vec<usize>) {
        let g = self.grid as isize;
        for dz in -r..=r {
            for dy in -r..=r {
                for dx in -r..=r {
                    if dx.abs().max(dy.abs()).max(dz.abs()) != r {
                        continue;
                    }
                    let (x, y, z) = (c[0] as isize + dx, c[1] as isize + dy, c[2] as isize + dz);
                    if x < 0 || y < 0 || z < 0 || x >= g || y >= g || z >= g {
                        continue;
                    }
                    let key = self.key([x as usize, y as usize, z as usize]);
                    let (s, e) = (self.starts[key] as usize, self.starts[key + 1] as usize);
                    out.extend(self.items[s..e].iter().map(|i| *i as usize));
                }
            }
        }
    }

    /// Exact solid angle (sr) of direction `i`'s spherical Voronoi cell (0 for a merged direction),
    /// or `None` when the cell reaches more than ~85° from its generator (very sparse sets).
    ///
    /// The cell is the intersection of the half-spaces `x·(d_i − d_j) ≥ 0`; in the gnomonic projection
    /// around `d_i` each is a half-plane, so the cell is a convex polygon clipped from a large square.
    /// Neighbours are gathered shell by shell from the bucket grid until every unvisited generator
    /// is farther than twice the cell's radius (so it cannot clip it). The area is the sum of the
    /// spherical triangles (d_i, v_k, v_k+1) (Van Oosterom–Strackee).
    pub fn cell_solid_angle(&self, i: usize) -> Option<f64> {
        let di = *self.dirs.get(i)?;
        if self.merged[i] {
            return Some(0.0);
        }
        let (e1, e2) = di.any_orthonormal_pair();
        const LIMIT: f64 = 11.43; // tan 85°
        let c = self.coords(di);
        let mut cands: Vec<usize> = Vec::new();
        let mut r = 0isize;
        loop {
            self.shell(c, r, &mut cands);
            let mut poly = vec![
                DVec2::new(-LIMIT, -LIMIT),
                DVec2::new(LIMIT, -LIMIT),
                DVec2::new(LIMIT, LIMIT),
                DVec2::new(-LIMIT, LIMIT),
            ];
            for &j in &cands {
                if j == i {
                    continue;
                }
                let n = di - self.dirs[j];
                poly = clip(&poly, n.dot(e1), n.dot(e2), n.dot(di));
                if poly.is_empty() {
                    return Some(0.0);
                }
            }
            let verts: Vec<DVec3> = poly.iter().map(|p| (di + p.x * e1 + p.y * e2).normalize()).collect();
            let reach = verts.iter().map(|v| (*v - di).length()).fold(0.0, f64::max);
            let searched_all = r + 1 >= self.grid as isize;
            if searched_all || 2.0 * reach <= r as f64 * self.cell {
                if poly.iter().any(|p| p.x.abs().max(p.y.abs()) >= LIMIT * (1.0 - 1e-9)) {
                    return None;
                }
                let mut area = 0.0;
                for k in 0..verts.len() {
                    let (a, b) = (verts[k], verts[(k + 1) % verts.len()]);
                    let num = di.dot(a.cross(b)).abs();
                    let den = 1.0 + di.dot(a) + a.dot(b) + b.dot(di);
                    area += 2.0 * num.atan2(den);
                }
                return Some(area);
            }
            r += 1;
        }
    }

    /// Solid angle (sr) of every direction's spherical Voronoi cell, exact
    /// ([`NearestDirection::cell_solid_angle`]) where every cell stays within ~85° of its generator,
    /// else estimated by sampling 2²² directions; returns the values and whether they are exact.
    pub fn solid_angles(&self) -> (Vec<f64>, bool) {
        let exact: Option<Vec<f64>> = (0..self.dirs.len())
            .into_par_iter()
            .map(|i| self.cell_solid_angle(i))
            .collect();
        match exact {
            Some(v) => (v, true),
            None => (self.voronoi_solid_angles(1 << 22), false),
        }
    }

    /// Solid angle (sr) of each direction's spherical Voronoi cell, estimated from `samples`
    /// Fibonacci-lattice directions (each worth 4π/`samples` sr). They sum to 4π.
    pub fn voronoi_solid_angles(&self, samples: usize) -> Vec<f64> {
        let m = samples.max(1);
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let n = self.dirs.len();
        let counts = (0..m)
            .into_par_iter()
            .fold(
                || vec![0u64; n],
                |mut acc, i| {
                    let z = 1.0 - (2.0 * i as f64 + 1.0) / m as f64;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let a = golden * i as f64;
                    if let Some(j) = self.nearest(DVec3::new(r * a.cos(), r * a.sin(), z)) {
                        acc[j] += 1;
                    }
                    acc
                },
            )
            .reduce(
                || vec![0u64; n],
                |mut a, b| {
                    a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                    a
                },
            );
        let w = 4.0 * std::f64::consts::PI / m as f64;
        counts.into_iter().map(|c| c as f64 * w).collect()
    }
}

/// Clips a convex polygon (gnomonic coordinates) to the half-plane `a·u + b·v + c ≥ 0`.
fn clip(poly: &[DVec2], a: f64, b: f64, c: f64) -> Vec<DVec2> {
    let side = |p: DVec2| a * p.x + b * p.y + c;
    let mut out = Vec::with_capacity(poly.len() + 1);
    for k in 0..poly.len() {
        let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
        let (sp, sq) = (side(p), side(q));
        if sp >= 0.0 {
            out.push(p);
        }
        if (sp >= 0.0) != (sq >= 0.0) {
            let t = sp / (sp - sq);
            out.push(p + (q - p) * t);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nearfield::layout::{self, Layout};

    #[test]
    fn nearest_matches_brute_force() {
        let dirs: Vec<DVec3> = layout::directions(&Layout::Fibonacci { count: 500 }, 0)
            .unwrap()
            .into_iter()
            .map(|(d, _)| d)
            .collect();
        let nd = NearestDirection::new(&dirs);
        let mut rng = layout::SplitMix64::new(3);
        for _ in 0..2000 {
            let k = DVec3::new(
                rng.next_f64() * 2.0 - 1.0,
                rng.next_f64() * 2.0 - 1.0,
                rng.next_f64() * 2.0 - 1.0,
            )
            .normalize();
            let brute = (0..dirs.len())
                .max_by(|&a, &b| dirs[a].dot(k).total_cmp(&dirs[b].dot(k)))
                .unwrap();
            assert_eq!(nd.nearest(k), Some(brute));
        }
        // Sparse sets: the search must widen until it is sure.
        let nd = NearestDirection::new(&[DVec3::X, -DVec3::X]);
        assert_eq!(nd.nearest(DVec3::new(0.1, 1.0, 0.0).normalize()), Some(0));
        assert_eq!(nd.nearest(-DVec3::Z + DVec3::X * -0.01), Some(1));
        let omega = NearestDirection::new(&[DVec3::Z, -DVec3::Z]).voronoi_solid_angles(10_000);
        assert!((omega[0] - 2.0 * std::f64::consts::PI).abs() < 1e-9);
    }

    #[test]
    fn exact_cells_tile_the_sphere_and_match_sampling() {
        let four_pi = 4.0 * std::f64::consts::PI;
        for l in [
            Layout::Fibonacci { count: 300 },
            Layout::Grid {
                phi_steps: 12,
                theta_steps: 7,
            },
            Layout::Rigo {
                per_hemisphere: 600,
                overlap_deg: 2.0,
                jitter_deg: 0.05,
            },
        ] {
            let d: Vec<DVec3> = layout::directions(&l, 1).unwrap().into_iter().map(|x| x.0).collect();
            let nd = NearestDirection::new(&d);
            let (exact, is_exact) = nd.solid_angles();
            assert!(is_exact, "{l:?}");
            let total: f64 = exact.iter().sum();
            assert!((total - four_pi).abs() < 1e-9, "{l:?}: {total}");
            let sampled = nd.voronoi_solid_angles(1 << 20);
            for (i, (e, s)) in exact.iter().zip(&sampled).enumerate() {
                // Sampling error: about 1/√(samples per cell) of the boundary's share.
                assert!(
                    (e - s).abs() < 0.05 * e.max(4.0 * four_pi / (1 << 16) as f64),
                    "{l:?} cell {i}: {e} vs {s}"
                );
            }
        }
        // Hemispheres are too wide for the gnomonic clip: sampled instead.
        let (h, is_exact) = NearestDirection::new(&[DVec3::Z, -DVec3::Z]).solid_angles();
        assert!(!is_exact && (h[0] - 0.5 * four_pi).abs() < 1e-9);
        // A regular octahedron: 8 equal faces' duals, 6 cells of 4π/6.
        let oct = [DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
        let nd = NearestDirection::new(&oct);
        for i in 0..6 {
            let a = nd.cell_solid_angle(i).unwrap();
            assert!((a - four_pi / 6.0).abs() < 1e-12, "{a}");
        }
    }

    #[test]
    fn coincident_directions_go_to_the_first() {
        let nd = NearestDirection::new(&[DVec3::Z, DVec3::X, DVec3::Z]);
        assert_eq!(nd.nearest(DVec3::new(0.01, 0.0, 1.0).normalize()), Some(0));
        let o = nd.voronoi_solid_angles(4096);
        assert_eq!(o[2], 0.0);
        assert_eq!(nd.cell_solid_angle(2), Some(0.0));
    }
}

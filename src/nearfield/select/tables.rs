//! The per-cell candidate lists (CSR): triangles whose spherical triangle meets a cell's cap, and the
//! vertices that can be among the 1 or 4 nearest of a point in a cell's cap.

use std::f64::consts::PI;

use glam::DVec3;
use rayon::prelude::*;

use super::grid::CellGrid;
use super::spherical::{angle, SphericalTriangle};
use crate::nearfield::error::{NearfieldError, Result};

/// Per-cell lists in CSR form: cell `c` holds `items[offsets[c]..offsets[c + 1]]`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(super) struct Csr {
    /// `cells + 1` offsets into `items`, non-decreasing, first 0, last `items.len()`.
    pub offsets: Vec<u32>,
    /// The concatenated lists.
    pub items: Vec<u32>,
}

impl Csr {
    /// The list of `cell` (empty when out of range).
    pub fn list(&self, cell: usize) -> &[u32] {
        match (self.offsets.get(cell), self.offsets.get(cell.saturating_add(1))) {
            (Some(&a), Some(&b)) => self.items.get(a as usize..b as usize).unwrap_or(&[]),
            _ => &[],
        }
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Mean and largest list length.
    pub fn len_stats(&self) -> (f64, usize) {
        let max = self
            .offsets
            .windows(2)
            .map(|w| (w[1] - w[0]) as usize)
            .max()
            .unwrap_or(0);
        let mean = self.items.len() as f64 / self.cells().max(1) as f64;
        (mean, max)
    }

    /// From per-cell counts and the concatenated items.
    fn from_counts(counts: impl Iterator<Item = usize>, items: Vec<u32>, what: &str) -> Result<Self> {
        if items.len() > u32::MAX as usize {
            return Err(NearfieldError::invalid(
                "cell_deg",
                format!("the {what} lists hold more than 2³² entries: use larger cells"),
            ));
        }
        let mut offsets = vec![0u32];
        let mut at = 0usize;
        for n in counts {
            at += n;
            offsets.push(at as u32);
        }
        Ok(Self { offsets, items })
    }
}

/// Triangles per cell: every listed triangle whose spherical triangle meets the cell's cap, found through
/// the cells near the triangle's enclosing cap and tested exactly; within a cell sorted by the angle
/// from the cell centre to the triangle's circumcentre (likely hits first), then by index.
pub(super) fn triangle_lists(
    grid: &CellGrid,
    tris: &[SphericalTriangle],
    circumcap: &[(DVec3, f64)],
    listed: &[bool],
) -> Result<Csr> {
    let rho_max = grid.rho_max();
    let mut pairs: Vec<(u32, u64, u32)> = (0..tris.len())
        .into_par_iter()
        .filter(|&t| listed[t])
        .flat_map_iter(|t| {
            let tri = &tris[t];
            let (cc, cr) = circumcap[t];
            let (m, r) = tri.enclosing_cap(cc, cr);
            let mut out = Vec::new();
            grid.for_each_cell_near(m, r + rho_max, |cell| {
                let c = grid.centre(cell);
                if tri.meets_cap(c, grid.rho(cell)) {
                    out.push((cell as u32, angle(c, cc).to_bits(), t as u32));
                }
            });
            out
        })
        .collect();
    pairs.par_sort_unstable();
    let mut counts = vec![0usize; grid.cells()];
    for p in &pairs {
        counts[p.0 as usize] += 1;
    }
    let items = pairs.into_iter().map(|p| p.2).collect();
    Csr::from_counts(counts.into_iter(), items, "triangle")
}

/// Vertex ids per cell of the grid (the buckets of the range queries), ascending.
fn buckets(grid: &CellGrid, dirs: &[DVec3]) -> Csr {
    let cell: Vec<usize> = dirs.par_iter().map(|d| grid.cell_of(*d)).collect();
    let mut counts = vec![0usize; grid.cells()];
    for &c in &cell {
        counts[c] += 1;
    }
    let mut offsets = Vec::with_capacity(counts.len() + 1);
    let mut at = 0u32;
    offsets.push(0);
    for &n in &counts {
        at += n as u32;
        offsets.push(at);
    }
    let mut fill: Vec<u32> = offsets[..counts.len()].to_vec();
    let mut items = vec![0u32; dirs.len()];
    for (v, &c) in cell.iter().enumerate() {
        items[fill[c] as usize] = v as u32;
        fill[c] += 1;
    }
    Csr { offsets, items }
}

/// How many of a cell's nearest vertices serve as references of the dominance test.
const DOMINANCE_REFS: usize = 32;

/// Whether `w` is strictly nearer than `v` to every point of the cap (centre `c`, radius ρ, given as
/// sin ρ with ρ < π/2): x · (w − v) > 0 over the cap ⟺ the cap lies beyond the bisecting great circle,
/// c · (w − v) > |w − v| sin ρ (with a 10⁻¹² margin).
fn dominates(w: DVec3, v: DVec3, c: DVec3, sin_rho: f64) -> bool {
    let m = w - v;
    c.dot(m) > m.length() * sin_rho + 1e-12
}

/// The k = 1 and k = 4 nearest-vertex candidate lists of every cell.
///
/// For the cell's cap (centre c, radius ρ): d_k = angle from c to its k-th nearest vertex; the list holds
/// the vertices within min(d_k + 2ρ, max_gap + ρ) of c, ascending, less those that k reference vertices
/// (the nearest to c) each dominate: nearer to every point of the cap, or of each piece of the cell's
/// cover ([`CellGrid::cover`]: the cell and its fp32 margin). Such a vertex has k strictly nearer
/// vertices at every point the query may bring to this cell, which the query also keeps (nearer, so
/// within the gap whenever it is), so it is never among the k selected. `r0` is the first search radius
/// (it grows until the k-th nearest and everything within d_k + 2ρ are found, or it reaches the gap
/// bound). `dirs.len()` must fit in u32.
pub(super) fn near_lists(grid: &CellGrid, dirs: &[DVec3], max_gap: f64, r0: f64) -> Result<(Csr, Csr)> {
    let buckets = buckets(grid, dirs);
    let n_phi = grid.n_phi as usize;
    type Row = (Vec<usize>, Vec<u32>, Vec<usize>, Vec<u32>);
    let rows: Vec<Row> = (0..grid.n_theta as usize)
        .into_par_iter()
        .map(|j| {
            let mut row: Row = Default::default();
            let mut found: Vec<(f64, u32)> = Vec::new();
            for cell in j * n_phi..(j + 1) * n_phi {
                let (c, rho) = (grid.centre(cell), grid.rho(cell));
                let limit = (max_gap + rho).min(PI);
                let mut r = (r0 + 2.0 * rho).min(limit);
                let (d1, d4) = loop {
                    found.clear();
                    grid.for_each_cell_near(c, r, |b| {
                        for &v in buckets.list(b) {
                            let a = angle(c, dirs[v as usize]);
                            if a <= r {
                                found.push((a, v));
                            }
                        }
                    });
                    found.sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
                    let kth = |k: usize| found.get(k - 1).map_or(f64::INFINITY, |f| f.0);
                    let (d1, d4) = (kth(1), kth(4));
                    if r >= limit {
                        break (d1, d4);
                    }
                    if d4.is_finite() && d4 + 2.0 * rho <= r {
                        break (d1, d4);
                    }
                    r = if d4.is_finite() {
                        (d4 + 2.0 * rho + 1e-9).min(limit)
                    } else {
                        (2.0 * r).min(limit)
                    };
                };
                // Dominance references: the nearest vertices of c (more would only tighten further).
                let refs: Vec<DVec3> = found.iter().take(DOMINANCE_REFS).map(|f| dirs[f.1 as usize]).collect();
                let whole = (c, rho.min(0.5 * PI).sin());
                let cover: Vec<(DVec3, f64)> = grid
                    .cover(cell)
                    .into_iter()
                    .map(|(pc, pr)| (pc, pr.min(0.5 * PI).sin()))
                    .collect();
                for (k, d, counts, items) in [(1, d1, &mut row.0, &mut row.1), (4, d4, &mut row.2, &mut row.3)] {
                    let bound = (d + 2.0 * rho).min(limit) + 1e-12;
                    let start = items.len();
                    for f in found.iter().filter(|f| f.0 <= bound) {
                        let v = dirs[f.1 as usize];
                        let free = |&(sc, sin_r): &(DVec3, f64)| {
                            refs.iter().filter(|&&w| dominates(w, v, sc, sin_r)).take(k).count() < k
                        };
                        // Over the whole cap first (quick), then over at least one piece of the cover.
                        if free(&whole) && cover.iter().any(free) {
                            items.push(f.1);
                        }
                    }
                    items[start..].sort_unstable();
                    counts.push(items.len() - start);
                }
            }
            row
        })
        .collect();
    let (mut c1, mut i1, mut c4, mut i4) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (a, b, c, d) in rows {
        c1.extend(a);
        i1.extend(b);
        c4.extend(c);
        i4.extend(d);
    }
    Ok((
        Csr::from_counts(c1.into_iter(), i1, "nearest")?,
        Csr::from_counts(c4.into_iter(), i4, "4-nearest")?,
    ))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn csr_lists_and_out_of_range() {
        let c = Csr::from_counts([2usize, 0, 1].into_iter(), vec![5, 6, 7], "t").unwrap();
        assert_eq!(c.offsets, vec![0, 2, 2, 3]);
        assert_eq!(c.list(0), &[5, 6]);
        assert!(c.list(1).is_empty());
        assert_eq!(c.list(2), &[7]);
        assert!(c.list(3).is_empty());
        assert!(c.list(usize::MAX).is_empty());
        assert_eq!(c.len_stats(), (1.0, 2));
    }

    #[test]
    fn buckets_hold_each_vertex_once_in_its_cell() {
        let g = CellGrid::new(8);
        let dirs: Vec<DVec3> = (0..50)
            .map(|k| DVec3::new((k as f64).sin(), (k as f64 * 1.7).cos(), (k as f64 * 0.3).sin()).normalize())
            .collect();
        let b = buckets(&g, &dirs);
        assert_eq!(b.items.len(), 50);
        for cell in 0..g.cells() {
            for &v in b.list(cell) {
                assert_eq!(g.cell_of(dirs[v as usize]), cell);
            }
        }
    }
}

//! [`SelectionStats`]: a summary of a [`Selection`] for reports (sizes, list lengths, the
//! medians and the gap it was built with, its GPU bytes).

use std::fmt;

use super::Selection;

/// A summary of a [`Selection`] for reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectionStats {
    /// Cameras of the set.
    pub cameras: usize,
    /// Vertices (unique directions).
    pub vertices: usize,
    /// Coincident camera groups merged into one vertex each.
    pub merged_groups: usize,
    /// Triangles (2 · vertices − 4).
    pub triangles: usize,
    /// Hole triangles (folded ones included).
    pub holes: usize,
    /// Folded triangles: the camera directions do not surround the centre (see the module docs); 0 for
    /// any scan that measured both hemispheres or one hemisphere plus an overlap.
    pub folded: usize,
    /// Grid columns (φ).
    pub n_phi: u32,
    /// Grid rows (θ).
    pub n_theta: u32,
    /// Mean triangles per cell.
    pub tri_list_mean: f64,
    /// Most triangles in a cell.
    pub tri_list_max: usize,
    /// Mean vertices per cell, k = 1.
    pub near1_list_mean: f64,
    /// Most vertices in a cell, k = 1.
    pub near1_list_max: usize,
    /// Mean vertices per cell, k = 4.
    pub near4_list_mean: f64,
    /// Most vertices in a cell, k = 4.
    pub near4_list_max: usize,
    /// Median edge of the non-hole triangles (degrees).
    pub median_edge_deg: f64,
    /// Median circumradius (degrees).
    pub median_circumradius_deg: f64,
    /// The gap beyond which Nearest/Idw4 find nothing (degrees).
    pub max_gap_deg: f64,
    /// Bytes of [`Selection::gpu_data`].
    pub gpu_bytes: u64,
}

impl fmt::Display for SelectionStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "selection: {} cameras, {} vertices ({} merged groups), {} triangles, {} holes ({} folded)",
            self.cameras, self.vertices, self.merged_groups, self.triangles, self.holes, self.folded
        )?;
        writeln!(
            f,
            "  grid {} × {} cells; median edge {:.3}°, median circumradius {:.3}°, max gap {:.3}°",
            self.n_phi, self.n_theta, self.median_edge_deg, self.median_circumradius_deg, self.max_gap_deg
        )?;
        write!(
            f,
            "  lists mean/max: triangles {:.2}/{}, nearest {:.2}/{}, 4-nearest {:.2}/{}; GPU {:.1} MiB",
            self.tri_list_mean,
            self.tri_list_max,
            self.near1_list_mean,
            self.near1_list_max,
            self.near4_list_mean,
            self.near4_list_max,
            self.gpu_bytes as f64 / f64::from(1u32 << 20)
        )
    }
}

impl Selection {
    /// A summary for reports.
    pub fn stats(&self) -> SelectionStats {
        let (tm, tx) = self.tri_cells.len_stats();
        let (n1m, n1x) = self.near1.len_stats();
        let (n4m, n4x) = self.near4.len_stats();
        SelectionStats {
            cameras: self.cameras,
            vertices: self.dirs.len(),
            merged_groups: self.merged_groups,
            triangles: self.tris.len(),
            holes: self.hole.iter().filter(|h| **h).count(),
            folded: self.folded.iter().filter(|f| **f).count(),
            n_phi: self.grid.n_phi,
            n_theta: self.grid.n_theta,
            tri_list_mean: tm,
            tri_list_max: tx,
            near1_list_mean: n1m,
            near1_list_max: n1x,
            near4_list_mean: n4m,
            near4_list_max: n4x,
            median_edge_deg: self.median_edge.to_degrees(),
            median_circumradius_deg: self.median_circumradius.to_degrees(),
            max_gap_deg: self.max_gap.to_degrees(),
            gpu_bytes: self.gpu_bytes(),
        }
    }
}

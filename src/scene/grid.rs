//! Calculation surfaces as a lighting designer reads them: the horizontal work plane `--grid H`
//! over the scene's floor, and its CSV.
//!
//! Promises:
//! - [`FloorRect::of_bounds`] is the scene's extent in X and Z (glTF's horizontal axes), inset by
//!   a margin on every side (0: the whole floor).
//! - [`work_plane_grid`] puts points on the plane y = H, normals +Y (light from above), at the
//!   centres of an nx × nz grid of equal cells covering the rectangle, with nx = ⌈width /
//!   spacing⌉ (so the actual spacing is at most the one asked for, and no point lies on a wall).
//!   Points run along X first, then Z.
//! - [`grid_csv`] writes `x_m,y_m,z_m,E_lx`, one line per point in order (coordinates to 0.1 mm,
//!   illuminance to 0.001 lx); [`write_grid_csv`] writes it through a temporary file renamed into
//!   place (`crate::files::TempOutput`).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use glam::DVec3;

use super::error::{Result, SceneError};
use super::model::Aabb;
use super::reference::SurfacePoint;

/// Most points of one grid (as `photometry::isolux`: about four million).
pub const MAX_GRID_POINTS: usize = 4_000_000;

/// A rectangle of the horizontal plane, scene metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorRect {
    /// Smallest X.
    pub x_min_m: f64,
    /// Largest X.
    pub x_max_m: f64,
    /// Smallest Z.
    pub z_min_m: f64,
    /// Largest Z.
    pub z_max_m: f64,
}

impl FloorRect {
    /// The scene's X–Z extent inset by `margin_m` on every side.
    ///
    /// Errors (argument `margin`): a margin that is negative, not finite, or leaves nothing.
    pub fn of_bounds(bounds: &Aabb, margin_m: f64) -> Result<Self> {
        let r = FloorRect {
            x_min_m: bounds.min.x + margin_m,
            x_max_m: bounds.max.x - margin_m,
            z_min_m: bounds.min.z + margin_m,
            z_max_m: bounds.max.z - margin_m,
        };
        if !(margin_m.is_finite() && margin_m >= 0.0 && r.x_max_m > r.x_min_m && r.z_max_m > r.z_min_m) {
            return Err(SceneError::invalid(
                "margin",
                format!(
                    "{margin_m} m inside a floor of {} × {} m leaves no area",
                    bounds.max.x - bounds.min.x,
                    bounds.max.z - bounds.min.z
                ),
            ));
        }
        Ok(r)
    }
}

/// The points of the work plane y = `height_m` over `rect`, cell centres at most `spacing_m`
/// apart, normals +Y.
///
/// Errors: a height that is not finite (argument `height`); a spacing that is not a finite number
/// greater than 0 (argument `spacing`); a rectangle that is empty or not finite (argument `rect`);
/// more than [`MAX_GRID_POINTS`] points (argument `spacing`).
pub fn work_plane_grid(rect: &FloorRect, height_m: f64, spacing_m: f64) -> Result<Vec<SurfacePoint>> {
    if !height_m.is_finite() {
        return Err(SceneError::invalid("height", format!("{height_m} m is not finite")));
    }
    if !(spacing_m.is_finite() && spacing_m > 0.0) {
        return Err(SceneError::invalid(
            "spacing",
            format!("{spacing_m} m: must be a finite number greater than 0"),
        ));
    }
    let (w, d) = (rect.x_max_m - rect.x_min_m, rect.z_max_m - rect.z_min_m);
    if !(w.is_finite() && d.is_finite() && w > 0.0 && d > 0.0) {
        return Err(SceneError::invalid("rect", format!("{rect:?} has no area")));
    }
    let (nx, nz) = ((w / spacing_m).ceil(), (d / spacing_m).ceil());
    if nx * nz > MAX_GRID_POINTS as f64 {
        return Err(SceneError::invalid(
            "spacing",
            format!("{spacing_m} m over {w} × {d} m gives {nx} × {nz} points; at most {MAX_GRID_POINTS}"),
        ));
    }
    let (nx, nz) = (nx as usize, nz as usize);
    let mut out = Vec::with_capacity(nx * nz);
    for k in 0..nz {
        for i in 0..nx {
            out.push(SurfacePoint {
                position_m: DVec3::new(
                    rect.x_min_m + (i as f64 + 0.5) * w / nx as f64,
                    height_m,
                    rect.z_min_m + (k as f64 + 0.5) * d / nz as f64,
                ),
                normal: DVec3::Y,
            });
        }
    }
    Ok(out)
}

/// The CSV text of illuminances at points: header `x_m,y_m,z_m,E_lx`, then one line per point.
///
/// Errors (argument `illuminance_lx`): a length other than the points'.
pub fn grid_csv(points: &[SurfacePoint], illuminance_lx: &[f64]) -> Result<String> {
    if points.len() != illuminance_lx.len() {
        return Err(SceneError::invalid(
            "illuminance_lx",
            format!("{} values for {} points", illuminance_lx.len(), points.len()),
        ));
    }
    let mut s = String::from("x_m,y_m,z_m,E_lx\n");
    for (p, e) in points.iter().zip(illuminance_lx) {
        let q = p.position_m;
        let _ = writeln!(s, "{:.4},{:.4},{:.4},{:.3}", q.x, q.y, q.z, e);
    }
    Ok(s)
}

/// Writes [`grid_csv`] to `path` (through a temporary file renamed into place).
///
/// Errors: those of [`grid_csv`]; I/O errors naming `path`.
pub fn write_grid_csv(path: &Path, points: &[SurfacePoint], illuminance_lx: &[f64]) -> Result<()> {
    let text = grid_csv(points, illuminance_lx)?;
    let io = |e| SceneError::io(path, e);
    let (mut out, _stale) = crate::files::TempOutput::create(path).map_err(io)?;
    let file = out
        .file()
        .ok_or_else(|| SceneError::invalid("output", "temporary file not open"))?;
    file.write_all(text.as_bytes()).map_err(io)?;
    out.commit().map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_covers_the_floor_at_cell_centres() {
        let b = Aabb {
            min: DVec3::new(-3.0, 0.0, -2.0),
            max: DVec3::new(3.0, 3.0, 2.0),
        };
        let r = FloorRect::of_bounds(&b, 0.5).unwrap();
        assert_eq!((r.x_min_m, r.x_max_m, r.z_min_m, r.z_max_m), (-2.5, 2.5, -1.5, 1.5));
        let g = work_plane_grid(&r, 0.75, 0.5).unwrap();
        assert_eq!(g.len(), 10 * 6);
        assert_eq!(g[0].position_m, DVec3::new(-2.25, 0.75, -1.25));
        assert_eq!(g[1].position_m.x, -1.75, "along X first");
        assert_eq!(g[59].position_m, DVec3::new(2.25, 0.75, 1.25));
        assert!(g.iter().all(|p| p.normal == DVec3::Y));
        // 0.45 m asked over 5 m: 12 cells of 0.4167 m.
        let g = work_plane_grid(&r, 0.8, 0.45).unwrap();
        assert_eq!(g.len(), 12 * 7);
        for (bad, arg) in [(f64::NAN, "spacing"), (0.0, "spacing"), (1e-5, "spacing")] {
            let e = work_plane_grid(&r, 0.8, bad).unwrap_err().to_string();
            assert!(e.contains(arg), "{e}");
        }
        assert!(work_plane_grid(&r, f64::INFINITY, 0.5)
            .unwrap_err()
            .to_string()
            .contains("height"));
        assert!(FloorRect::of_bounds(&b, 2.0)
            .unwrap_err()
            .to_string()
            .contains("margin"));
        assert!(FloorRect::of_bounds(&b, -0.1).is_err());
    }

    #[test]
    fn csv_has_the_issue_columns() {
        let p = [SurfacePoint {
            position_m: DVec3::new(1.0, 0.75, -0.25),
            normal: DVec3::Y,
        }];
        let s = grid_csv(&p, &[512.34567]).unwrap();
        assert_eq!(s, "x_m,y_m,z_m,E_lx\n1.0000,0.7500,-0.2500,512.346\n");
        assert!(grid_csv(&p, &[]).is_err());
        let dir = std::env::temp_dir().join(format!("lumiview-grid-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("grid.csv");
        write_grid_csv(&f, &p, &[1.0]).unwrap();
        assert_eq!(
            std::fs::read_to_string(&f).unwrap(),
            "x_m,y_m,z_m,E_lx\n1.0000,0.7500,-0.2500,1.000\n"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}

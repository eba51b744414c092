//! Camera coverage of a scan: how well the cameras cover the directions around the luminaire.
//!
//! - [`CameraIndex`]: nearest-camera queries over the unit directions of the cameras (a k-d tree over
//!   the unit vectors; O(log n) per query and insensitive to empty regions such as a missing
//!   hemisphere). Distances are great-circle angles, never planar (Δφ, Δθ).
//! - [`Coverage`]: per-hemisphere counts, coincident positions, and the distribution of the angle
//!   from a direction to its nearest camera over the whole sphere (median, 95th percentile and
//!   maximum over [`STATS_SAMPLES`] uniformly spread directions; the maximum is then refined towards
//!   the nearest vertex of the cameras' spherical Voronoi diagram, where the true maximum lies).
//! - [`Coverage::to_png`]: a picture (`lumiview cameras`): left, the camera positions on two
//!   Lambert equal-area discs (lower hemisphere seen from below, upper seen from above, each to 100°
//!   from its pole so the overlap at the equator shows), cameras coloured by hemisphere; right, an
//!   equirectangular map (φ across, θ up: zenith at the top) of the angle to the nearest camera,
//!   with a colour bar.

use glam::DVec3;
use rayon::prelude::*;
use tiny_skia::{Color, FillRule, Paint, PathBuilder, Pixmap, Rect, Stroke, StrokeDash, Transform};

use super::error::{NearfieldError, Result};
use super::rayset::{Hemisphere, RayImageSet};
use crate::draw::colormap::VIRIDIS;
use crate::draw::text::{Anchor, Typeface, FONT_PATH};
use crate::draw::ticks::{label_at_step, step_at_least};

/// Uniformly spread directions (a Fibonacci sphere) over which the gap statistics are taken.
pub const STATS_SAMPLES: usize = 1 << 18;

/// Smallest accepted picture width, pixels.
pub const MIN_WIDTH_PX: u32 = 640;

/// Largest accepted picture width, pixels.
pub const MAX_WIDTH_PX: u32 = 8192;

/// Points per k-d tree leaf.
const LEAF: usize = 8;

/// Great-circle angle (rad) of the chord between two unit vectors, from its squared length.
fn chord2_to_angle(c2: f64) -> f64 {
    2.0 * (c2.max(0.0).sqrt() / 2.0).min(1.0).asin()
}

/// Nearest-camera queries on the unit sphere (a k-d tree over unit vectors; the nearest in chord
/// length is the nearest in great-circle angle).
#[derive(Debug, Clone)]
pub struct CameraIndex {
    /// The points in tree order.
    points: Vec<DVec3>,
    /// Original index of each point.
    ids: Vec<usize>,
    /// Split axis of the node whose median sits at each position.
    axis: Vec<u8>,
}

impl CameraIndex {
    /// An index over `dirs` (unit vectors; query results refer to positions in `dirs`). Non-finite or
    /// zero-length entries are left out.
    pub fn new(dirs: &[DVec3]) -> Self {
        let mut items: Vec<(DVec3, usize)> = dirs
            .iter()
            .enumerate()
            .filter(|(_, d)| d.is_finite() && d.length_squared() > 0.25)
            .map(|(i, d)| (d.normalize(), i))
            .collect();
        let mut axis = vec![0u8; items.len()];
        build(&mut items, 0, &mut axis);
        Self {
            points: items.iter().map(|(p, _)| *p).collect(),
            ids: items.iter().map(|(_, i)| *i).collect(),
            axis,
        }
    }

    /// Number of indexed directions.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether no direction is indexed.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The nearest direction to the unit vector `q`: (its index in the input, great-circle angle in
    /// rad); `None` when the index is empty.
    pub fn nearest(&self, q: DVec3) -> Option<(usize, f64)> {
        let mut best = KBest::new(1);
        self.search(0, self.points.len(), q, &mut best);
        best.items.first().map(|&(c2, i)| (self.ids[i], chord2_to_angle(c2)))
    }

    /// The `k` nearest directions to `q`, nearest first, as (index in the input, angle in rad).
    pub fn k_nearest(&self, q: DVec3, k: usize) -> Vec<(usize, f64)> {
        let mut best = KBest::new(k);
        if k > 0 {
            self.search(0, self.points.len(), q, &mut best);
        }
        best.items
            .iter()
            .map(|&(c2, i)| (self.ids[i], chord2_to_angle(c2)))
            .collect()
    }

    fn search(&self, lo: usize, hi: usize, q: DVec3, best: &mut KBest) {
        let n = hi - lo;
        if n <= LEAF {
            for i in lo..hi {
                best.offer((self.points[i] - q).length_squared(), i);
            }
            return;
        }
        let mid = lo + n / 2;
        let a = usize::from(self.axis[mid]);
        let diff = q[a] - self.points[mid][a];
        best.offer((self.points[mid] - q).length_squared(), mid);
        let (near, far) = if diff < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(near.0, near.1, q, best);
        if diff * diff < best.bound() {
            self.search(far.0, far.1, q, best);
        }
    }
}

/// Builds the implicit k-d tree in place: the median of each range on the axis of largest extent.
fn build(items: &mut [(DVec3, usize)], offset: usize, axis: &mut [u8]) {
    if items.len() <= LEAF {
        return;
    }
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for (p, _) in items.iter() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let e = hi - lo;
    let a: u8 = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    let ai = usize::from(a);
    items.select_nth_unstable_by(mid, |x, y| x.0[ai].total_cmp(&y.0[ai]));
    axis[offset + mid] = a;
    let (left, right) = items.split_at_mut(mid);
    build(left, offset, axis);
    build(&mut right[1..], offset + mid + 1, axis);
}

/// The k smallest (squared chord, position) pairs seen, sorted.
struct KBest {
    k: usize,
    items: Vec<(f64, usize)>,
}

impl KBest {
    fn new(k: usize) -> Self {
        Self {
            k,
            items: Vec::with_capacity(k + 1),
        }
    }
    fn bound(&self) -> f64 {
        if self.items.len() < self.k {
            f64::INFINITY
        } else {
            self.items.last().map_or(f64::INFINITY, |x| x.0)
        }
    }
    fn offer(&mut self, d2: f64, i: usize) {
        if d2 >= self.bound() {
            return;
        }
        let at = self.items.partition_point(|x| x.0 <= d2);
        self.items.insert(at, (d2, i));
        self.items.truncate(self.k);
    }
}

/// Photometric angles (φ, θ) in degrees of a unit direction (φ in 0…360).
fn angles_deg(d: DVec3) -> [f64; 2] {
    [
        d.y.atan2(d.x).to_degrees().rem_euclid(360.0),
        (-d.z).clamp(-1.0, 1.0).acos().to_degrees(),
    ]
}

/// Direction of photometric angles in degrees.
fn dir_deg(phi: f64, theta: f64) -> DVec3 {
    let (p, t) = (phi.to_radians(), theta.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), -t.cos())
}

/// The `i`-th of `n` Fibonacci-sphere directions (equal-area spread).
fn fibonacci(i: usize, n: usize) -> DVec3 {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let a = golden * i as f64;
    DVec3::new(r * a.cos(), r * a.sin(), z)
}

/// Summary of a scan's camera coverage.
#[derive(Debug, Clone, PartialEq)]
pub struct CoverageStats {
    /// Cameras in the scan.
    pub cameras: usize,
    /// Cameras tagged [`Hemisphere::Lower`].
    pub lower: usize,
    /// Cameras tagged [`Hemisphere::Upper`].
    pub upper: usize,
    /// Groups of cameras at the same position (within 10⁻⁶ rad), e.g. meridian starts at the poles.
    pub coincident_groups: usize,
    /// Cameras in those groups.
    pub cameras_in_coincident_groups: usize,
    /// Median over the sphere of the angle from a direction to its nearest camera, degrees.
    pub median_gap_deg: f64,
    /// 95th percentile of that angle, degrees.
    pub p95_gap_deg: f64,
    /// Largest angle found (sampled, then refined at Voronoi vertices), degrees: no direction found
    /// is farther from every camera.
    pub max_gap_deg: f64,
    /// Where the largest angle was found, (φ, θ) in degrees.
    pub max_gap_at_deg: [f64; 2],
    /// Directions sampled for the statistics.
    pub samples: usize,
}

/// The coverage analysis of a scan: stats plus what the picture needs.
#[derive(Debug, Clone)]
pub struct Coverage {
    /// The statistics.
    pub stats: CoverageStats,
    /// Unit directions of the cameras from the capture centre.
    dirs: Vec<DVec3>,
    /// Their hemisphere tags.
    hemispheres: Vec<Hemisphere>,
    /// Nearest-camera index over `dirs`.
    index: CameraIndex,
    /// Capture sphere radius (m), for the title.
    radius_m: f64,
}

impl Coverage {
    /// Analyses the cameras of `set` (O(n log n) plus [`STATS_SAMPLES`] queries, on all cores).
    pub fn new(set: &RayImageSet) -> Self {
        let dirs: Vec<DVec3> = set
            .cameras
            .iter()
            .map(|c| c.direction_from(set.sphere.centre_m))
            .collect();
        let hemispheres: Vec<Hemisphere> = set.cameras.iter().map(|c| c.hemisphere).collect();
        let index = CameraIndex::new(&dirs);
        let groups = set.coincident_groups(1e-6);
        let lower = hemispheres.iter().filter(|h| **h == Hemisphere::Lower).count();
        let mut stats = CoverageStats {
            cameras: dirs.len(),
            lower,
            upper: dirs.len() - lower,
            coincident_groups: groups.len(),
            cameras_in_coincident_groups: groups.iter().map(Vec::len).sum(),
            median_gap_deg: f64::NAN,
            p95_gap_deg: f64::NAN,
            max_gap_deg: f64::NAN,
            max_gap_at_deg: [f64::NAN; 2],
            samples: STATS_SAMPLES,
        };
        if !index.is_empty() {
            let gaps: Vec<f64> = (0..STATS_SAMPLES)
                .into_par_iter()
                .map(|i| index.nearest(fibonacci(i, STATS_SAMPLES)).map_or(f64::NAN, |(_, a)| a))
                .collect();
            let mut order: Vec<usize> = (0..STATS_SAMPLES).collect();
            order.sort_unstable_by(|&a, &b| gaps[a].total_cmp(&gaps[b]));
            let at = |q: f64| gaps[order[((STATS_SAMPLES - 1) as f64 * q).round() as usize]];
            stats.median_gap_deg = at(0.5).to_degrees();
            stats.p95_gap_deg = at(0.95).to_degrees();
            // Refine from the 64 widest sampled gaps towards the Voronoi vertices near them.
            let (max, where_) = order
                .iter()
                .rev()
                .take(64)
                .collect::<Vec<_>>()
                .par_iter()
                .map(|&&i| refine_gap(&index, &dirs, fibonacci(i, STATS_SAMPLES)))
                .reduce(|| (f64::NEG_INFINITY, DVec3::Z), |a, b| if b.0 > a.0 { b } else { a });
            stats.max_gap_deg = max.to_degrees();
            stats.max_gap_at_deg = angles_deg(where_);
        }
        Self {
            stats,
            dirs,
            hemispheres,
            index,
            radius_m: set.sphere.radius_m,
        }
    }

    /// The nearest-camera index.
    pub fn index(&self) -> &CameraIndex {
        &self.index
    }

    /// The angle (degrees) from each pixel centre of an equirectangular `width × height` map to its
    /// nearest camera: column c at φ = (c + 0.5)·360°/width, row r at θ = 180° − (r + 0.5)·180°/height
    /// (row 0 at the zenith). NaN when the scan has no camera.
    pub fn angle_map(&self, width: usize, height: usize) -> Vec<f32> {
        let mut out = vec![f32::NAN; width * height];
        if width == 0 {
            return out;
        }
        out.par_chunks_mut(width).enumerate().for_each(|(r, row)| {
            let theta = 180.0 - (r as f64 + 0.5) * 180.0 / height as f64;
            for (c, v) in row.iter_mut().enumerate() {
                let phi = (c as f64 + 0.5) * 360.0 / width as f64;
                if let Some((_, a)) = self.index.nearest(dir_deg(phi, theta)) {
                    *v = a.to_degrees() as f32;
                }
            }
        });
        out
    }

    /// The coverage picture as PNG bytes, `width_px` wide (height ≈ 0.39 × width).
    ///
    /// # Errors
    /// [`NearfieldError::InvalidArgument`] for a width outside [`MIN_WIDTH_PX`]…[`MAX_WIDTH_PX`] or
    /// when the picture cannot be drawn or encoded.
    pub fn to_png(&self, width_px: u32) -> Result<Vec<u8>> {
        if !(MIN_WIDTH_PX..=MAX_WIDTH_PX).contains(&width_px) {
            return Err(NearfieldError::invalid(
                "width",
                format!("{width_px} px is outside {MIN_WIDTH_PX}…{MAX_WIDTH_PX}"),
            ));
        }
        let pm = self.draw(width_px)?;
        pm.encode_png()
            .map_err(|e| NearfieldError::invalid("coverage picture", format!("PNG encoding: {e}")))
    }

    /// Writes [`Coverage::to_png`] to `path`.
    ///
    /// # Errors
    /// Those of [`Coverage::to_png`], and [`NearfieldError::Io`] naming `path`.
    pub fn write_png(&self, width_px: u32, path: &std::path::Path) -> Result<()> {
        let bytes = self.to_png(width_px)?;
        std::fs::write(path, bytes).map_err(|e| NearfieldError::io(path, e))
    }

    fn draw(&self, width_px: u32) -> Result<Pixmap> {
        let face = Typeface::load().map_err(|e| NearfieldError::format(FONT_PATH, e))?;
        let s = f64::from(width_px) / 1600.0;
        let height_px = (620.0 * s).round() as u32;
        let mut pm = Pixmap::new(width_px, height_px).ok_or_else(|| {
            NearfieldError::invalid(
                "coverage picture",
                format!("cannot allocate {width_px} × {height_px} px"),
            )
        })?;
        pm.fill(Color::WHITE);
        let ink = [30, 30, 30, 255];
        let grey = [110, 110, 110, 255];
        let st = &self.stats;
        face.text(
            &mut pm,
            &format!(
                "Camera coverage: {} cameras on a capture sphere of radius {} m",
                st.cameras,
                fmt_g(self.radius_m)
            ),
            40.0 * s,
            40.0 * s,
            24.0 * s,
            ink,
            Anchor::Start,
        );
        let gaps = if st.max_gap_deg.is_finite() {
            format!(
                "nearest-camera angle over the sphere: median {:.3}°, 95 % {:.3}°, max {:.3}° at φ {:.1}°, θ {:.1}°",
                st.median_gap_deg, st.p95_gap_deg, st.max_gap_deg, st.max_gap_at_deg[0], st.max_gap_at_deg[1]
            )
        } else {
            "no camera directions".to_string()
        };
        face.text(
            &mut pm,
            &format!(
                "{gaps}  ·  coincident positions: {} group(s), {} cameras",
                st.coincident_groups, st.cameras_in_coincident_groups
            ),
            40.0 * s,
            66.0 * s,
            14.0 * s,
            grey,
            Anchor::Start,
        );

        // Left: the two discs.
        let radius = 165.0 * s;
        let cy = 315.0 * s;
        let discs = [
            (
                235.0 * s,
                -DVec3::Z,
                "Lower hemisphere, seen from below",
                ["θ 30°", "60°", "90°"],
            ),
            (
                635.0 * s,
                DVec3::Z,
                "Upper hemisphere, seen from above",
                ["θ 150°", "120°", "90°"],
            ),
        ];
        for (cx, pole, title, ring_labels) in &discs {
            face.text(&mut pm, title, *cx, 110.0 * s, 15.0 * s, ink, Anchor::Middle);
            self.draw_disc(&mut pm, &face, [*cx, cy], radius, *pole, ring_labels, s);
        }
        // Legend below the discs.
        let lower_c = HEMI_COLOURS[0];
        let upper_c = HEMI_COLOURS[1];
        let ly = 540.0 * s;
        for (k, (c, label)) in [
            (lower_c, format!("lower hemisphere: {} cameras", st.lower)),
            (upper_c, format!("upper hemisphere: {} cameras", st.upper)),
        ]
        .iter()
        .enumerate()
        {
            let x = 90.0 * s + k as f64 * 360.0 * s;
            if let Some(p) = PathBuilder::from_circle(x as f32, (ly - 5.0 * s) as f32, (5.0 * s) as f32) {
                pm.fill_path(&p, &paint(*c), FillRule::Winding, Transform::identity(), None);
            }
            face.text(&mut pm, label, x + 12.0 * s, ly, 14.0 * s, ink, Anchor::Start);
        }
        face.text(
            &mut pm,
            "Lambert equal-area discs to 100° from each pole; dashed circle: the equator (θ 90°). C0 = +X, C90 = +Y.",
            40.0 * s,
            580.0 * s,
            12.0 * s,
            grey,
            Anchor::Start,
        );

        // Right: the nearest-camera angle map.
        self.draw_map(&mut pm, &face, s);
        Ok(pm)
    }

    #[allow(clippy::too_many_arguments)]
    fn draw_disc(
        &self,
        pm: &mut Pixmap,
        face: &Typeface,
        centre: [f64; 2],
        radius: f64,
        pole: DVec3,
        ring_labels: &[&str; 3],
        s: f64,
    ) {
        let id = Transform::identity();
        let reach = 100f64.to_radians();
        let scale = radius / (2.0 * (reach / 2.0).sin());
        let from_below = pole.z < 0.0;
        // Screen position of a unit direction, if within reach of the pole.
        let project = |d: DVec3| -> Option<[f64; 2]> {
            let alpha = d.dot(pole).clamp(-1.0, 1.0).acos();
            if alpha > reach + 1e-9 {
                return None;
            }
            let r = scale * 2.0 * (alpha / 2.0).sin();
            let h = (d.x * d.x + d.y * d.y).sqrt();
            let (ux, uy) = if h > 1e-12 { (d.x / h, d.y / h) } else { (0.0, 0.0) };
            // Seen from below (looking along +Z) +Y is down on screen; from above it is up.
            let sy = if from_below { uy } else { -uy };
            Some([centre[0] + r * ux, centre[1] + r * sy])
        };
        let ring = |alpha_deg: f64| scale * 2.0 * (alpha_deg.to_radians() / 2.0).sin();
        // Background and grid.
        if let Some(p) = PathBuilder::from_circle(centre[0] as f32, centre[1] as f32, radius as f32) {
            pm.fill_path(&p, &paint([247, 247, 247, 255]), FillRule::Winding, id, None);
        }
        let thin = Stroke {
            width: (0.8 * s) as f32,
            ..Stroke::default()
        };
        for a in [30.0, 60.0] {
            if let Some(p) = PathBuilder::from_circle(centre[0] as f32, centre[1] as f32, ring(a) as f32) {
                pm.stroke_path(&p, &paint([190, 190, 190, 255]), &thin, id, None);
            }
        }
        for k in 0..4 {
            let a = f64::from(k) * std::f64::consts::FRAC_PI_2;
            let mut pb = PathBuilder::new();
            pb.move_to(centre[0] as f32, centre[1] as f32);
            pb.line_to(
                (centre[0] + radius * a.cos()) as f32,
                (centre[1] + radius * a.sin()) as f32,
            );
            if let Some(p) = pb.finish() {
                pm.stroke_path(&p, &paint([190, 190, 190, 255]), &thin, id, None);
            }
        }
        // Cameras: lower-tagged first, upper-tagged on top (half transparent, so overlap shows).
        let inside: Vec<(usize, [f64; 2])> = self
            .dirs
            .iter()
            .enumerate()
            .filter_map(|(i, d)| project(*d).map(|p| (i, p)))
            .collect();
        let spacing = radius * (std::f64::consts::PI / inside.len().max(1) as f64).sqrt();
        let dot = (0.3 * spacing).clamp(0.7 * s, 4.0 * s);
        for (h, colour) in [
            (Hemisphere::Lower, HEMI_COLOURS[0]),
            (Hemisphere::Upper, HEMI_COLOURS[1]),
        ] {
            let mut pb = PathBuilder::new();
            let mut any = false;
            for (i, p) in &inside {
                if self.hemispheres[*i] == h {
                    pb.push_circle(p[0] as f32, p[1] as f32, dot as f32);
                    any = true;
                }
            }
            if any {
                if let Some(path) = pb.finish() {
                    let mut c = colour;
                    c[3] = 190;
                    pm.fill_path(&path, &paint(c), FillRule::Winding, id, None);
                }
            }
        }
        // Equator (dashed) and rim.
        let dashed = Stroke {
            width: (1.2 * s) as f32,
            dash: StrokeDash::new(vec![(6.0 * s) as f32, (4.0 * s) as f32], 0.0),
            ..Stroke::default()
        };
        if let Some(p) = PathBuilder::from_circle(centre[0] as f32, centre[1] as f32, ring(90.0) as f32) {
            pm.stroke_path(&p, &paint([40, 40, 40, 255]), &dashed, id, None);
        }
        let rim = Stroke {
            width: (1.2 * s) as f32,
            ..Stroke::default()
        };
        if let Some(p) = PathBuilder::from_circle(centre[0] as f32, centre[1] as f32, radius as f32) {
            pm.stroke_path(&p, &paint([90, 90, 90, 255]), &rim, id, None);
        }
        // Ring labels along the upper-right diagonal, C labels around the rim.
        let diag = -std::f64::consts::FRAC_PI_4;
        for (a, label) in [30.0, 60.0, 90.0].iter().zip(ring_labels) {
            let r = ring(*a) + 3.0 * s;
            face.text(
                pm,
                label,
                centre[0] + r * diag.cos(),
                centre[1] + r * diag.sin(),
                11.0 * s,
                [90, 90, 90, 255],
                Anchor::Start,
            );
        }
        let ysign = if from_below { 1.0 } else { -1.0 };
        let size = 12.0 * s;
        let gap = 6.0 * s;
        let c0 = [centre[0] + radius + gap, centre[1] + size * 0.36];
        face.text(pm, "C0", c0[0], c0[1], size, [30, 30, 30, 255], Anchor::Start);
        let c180 = [centre[0] - radius - gap, centre[1] + size * 0.36];
        face.text(pm, "C180", c180[0], c180[1], size, [30, 30, 30, 255], Anchor::End);
        let below = centre[1] + radius + gap + size * 0.75;
        let above = centre[1] - radius - gap;
        let (c90y, c270y) = if ysign > 0.0 { (below, above) } else { (above, below) };
        face.text(pm, "C90", centre[0], c90y, size, [30, 30, 30, 255], Anchor::Middle);
        face.text(pm, "C270", centre[0], c270y, size, [30, 30, 30, 255], Anchor::Middle);
    }

    fn draw_map(&self, pm: &mut Pixmap, face: &Typeface, s: f64) {
        let id = Transform::identity();
        let ink = [30, 30, 30, 255];
        let (x0, y0) = ((890.0 * s).round(), (150.0 * s).round());
        let (mw, mh) = ((640.0 * s).round() as usize, (320.0 * s).round() as usize);
        face.text(
            pm,
            "Angle to the nearest camera (great circle)",
            x0 + mw as f64 / 2.0,
            110.0 * s,
            15.0 * s,
            ink,
            Anchor::Middle,
        );
        let values = self.angle_map(mw, mh);
        let vmax_data = values.iter().copied().filter(|v| v.is_finite()).fold(0.0f32, f32::max);
        let vmax_data = f64::from(vmax_data).max(self.stats.max_gap_deg).max(1e-6);
        let step = step_at_least(vmax_data / 5.0);
        let vmax = (vmax_data / step).ceil() * step;
        // Pixels straight into the (opaque) pixmap.
        let (pw, ph) = (pm.width() as usize, pm.height() as usize);
        let data = pm.data_mut();
        for r in 0..mh {
            for c in 0..mw {
                let (x, y) = (x0 as usize + c, y0 as usize + r);
                if x >= pw || y >= ph {
                    continue;
                }
                let v = values[r * mw + c];
                let rgb = if v.is_finite() {
                    VIRIDIS.at(f64::from(v) / vmax)
                } else {
                    [200, 200, 200]
                };
                let i = (y * pw + x) * 4;
                data[i..i + 4].copy_from_slice(&[rgb[0], rgb[1], rgb[2], 255]);
            }
        }
        let (mwf, mhf) = (mw as f64, mh as f64);
        // Grid: φ every 90°, θ every 30° (equator dashed).
        let grid = Stroke {
            width: (0.8 * s) as f32,
            ..Stroke::default()
        };
        let line = |pm: &mut Pixmap, a: [f64; 2], b: [f64; 2], stroke: &Stroke, colour: [u8; 4]| {
            let mut pb = PathBuilder::new();
            pb.move_to(a[0] as f32, a[1] as f32);
            pb.line_to(b[0] as f32, b[1] as f32);
            if let Some(p) = pb.finish() {
                pm.stroke_path(&p, &paint(colour), stroke, id, None);
            }
        };
        for k in 1..4 {
            let x = x0 + mwf * f64::from(k) / 4.0;
            line(pm, [x, y0], [x, y0 + mhf], &grid, [255, 255, 255, 90]);
        }
        for k in 1..6 {
            let y = y0 + mhf * f64::from(k) / 6.0;
            if k == 3 {
                let dashed = Stroke {
                    width: (1.2 * s) as f32,
                    dash: StrokeDash::new(vec![(6.0 * s) as f32, (4.0 * s) as f32], 0.0),
                    ..Stroke::default()
                };
                line(pm, [x0, y], [x0 + mwf, y], &dashed, [255, 255, 255, 200]);
            } else {
                line(pm, [x0, y], [x0 + mwf, y], &grid, [255, 255, 255, 90]);
            }
        }
        if let Some(rect) = Rect::from_xywh(x0 as f32, y0 as f32, mwf as f32, mhf as f32) {
            let p = PathBuilder::from_rect(rect);
            pm.stroke_path(
                &p,
                &paint([60, 60, 60, 255]),
                &Stroke {
                    width: (1.0 * s) as f32,
                    ..Stroke::default()
                },
                id,
                None,
            );
        }
        // The widest gap found: a ring around it.
        let [gphi, gtheta] = self.stats.max_gap_at_deg;
        if gphi.is_finite() && gtheta.is_finite() {
            let gx = x0 + mwf * gphi / 360.0;
            let gy = y0 + mhf * (180.0 - gtheta) / 180.0;
            if let Some(p) = PathBuilder::from_circle(gx as f32, gy as f32, (7.0 * s) as f32) {
                let ring = Stroke {
                    width: (2.0 * s) as f32,
                    ..Stroke::default()
                };
                pm.stroke_path(&p, &paint([255, 255, 255, 255]), &ring, id, None);
                let inner = Stroke {
                    width: (1.0 * s) as f32,
                    ..Stroke::default()
                };
                pm.stroke_path(&p, &paint([200, 30, 30, 255]), &inner, id, None);
            }
        }
        // Axes.
        let size = 12.0 * s;
        for k in 0..=4 {
            let x = x0 + mwf * f64::from(k) / 4.0;
            face.text(
                pm,
                &format!("{}°", k * 90),
                x,
                y0 + mhf + 18.0 * s,
                size,
                ink,
                Anchor::Middle,
            );
        }
        face.text(
            pm,
            "φ = C (°)",
            x0 + mwf / 2.0,
            y0 + mhf + 38.0 * s,
            13.0 * s,
            ink,
            Anchor::Middle,
        );
        for k in 0..=6 {
            let y = y0 + mhf * f64::from(k) / 6.0;
            face.text(
                pm,
                &format!("{}°", 180 - 30 * k),
                x0 - 6.0 * s,
                y + size * 0.36,
                size,
                ink,
                Anchor::End,
            );
        }
        face.text(pm, "θ = γ (°)", x0 - 6.0 * s, y0 - 10.0 * s, 13.0 * s, ink, Anchor::End);
        face.text(
            pm,
            "zenith",
            x0 + mwf + 6.0 * s,
            y0 + size * 0.36,
            11.0 * s,
            [90, 90, 90, 255],
            Anchor::Start,
        );
        face.text(
            pm,
            "nadir",
            x0 + mwf + 6.0 * s,
            y0 + mhf + size * 0.36,
            11.0 * s,
            [90, 90, 90, 255],
            Anchor::Start,
        );
        // Colour bar.
        let (by, bh) = ((540.0 * s).round(), (14.0 * s).round());
        let bw = mw;
        let data = pm.data_mut();
        for c in 0..bw {
            let rgb = VIRIDIS.at((c as f64 + 0.5) / bw as f64);
            for r in 0..bh as usize {
                let (x, y) = (x0 as usize + c, by as usize + r);
                if x < pw && y < ph {
                    let i = (y * pw + x) * 4;
                    data[i..i + 4].copy_from_slice(&[rgb[0], rgb[1], rgb[2], 255]);
                }
            }
        }
        let ticks = (vmax / step).round() as i64;
        for k in 0..=ticks {
            let v = k as f64 * step;
            let x = x0 + mwf * v / vmax;
            line(pm, [x, by + bh], [x, by + bh + 4.0 * s], &grid, [60, 60, 60, 255]);
            face.text(
                pm,
                &label_at_step(v, step),
                x,
                by + bh + 17.0 * s,
                size,
                ink,
                Anchor::Middle,
            );
        }
        face.text(
            pm,
            "angle to the nearest camera (°); ring: the widest gap found",
            x0 + mwf / 2.0,
            by + bh + 37.0 * s,
            13.0 * s,
            ink,
            Anchor::Middle,
        );
    }
}

/// Refines a wide gap: moves from `q` to the spherical circumcentre of its three nearest distinct
/// cameras (a Voronoi vertex when no other camera is closer), a few times. Returns the largest
/// nearest-camera angle met (rad) and where; every value returned is a true nearest-camera angle.
fn refine_gap(index: &CameraIndex, dirs: &[DVec3], q0: DVec3) -> (f64, DVec3) {
    let Some((_, a0)) = index.nearest(q0) else {
        return (f64::NEG_INFINITY, q0);
    };
    let mut best = (a0, q0);
    let mut q = q0;
    for _ in 0..16 {
        let mut pts: Vec<DVec3> = Vec::with_capacity(3);
        for (i, _) in index.k_nearest(q, 16) {
            let p = dirs[i].normalize_or_zero();
            if pts.iter().all(|x| (*x - p).length() > 1e-9) {
                pts.push(p);
                if pts.len() == 3 {
                    break;
                }
            }
        }
        if pts.len() < 3 {
            break;
        }
        let n = (pts[1] - pts[0]).cross(pts[2] - pts[0]);
        if n.length() < 1e-15 {
            break;
        }
        let mut v = n.normalize();
        if v.dot(q) < 0.0 {
            v = -v;
        }
        let Some((_, a)) = index.nearest(v) else {
            break;
        };
        if a > best.0 {
            best = (a, v);
        }
        if (v - q).length() < 1e-12 {
            break;
        }
        q = v;
    }
    best
}

/// Colours of the lower and upper hemisphere's cameras.
const HEMI_COLOURS: [[u8; 4]; 2] = [[31, 119, 180, 255], [230, 97, 1, 255]];

/// A number without needless digits (for the title).
fn fmt_g(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

fn paint(c: [u8; 4]) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color_rgba8(c[0], c[1], c[2], c[3]);
    p.anti_alias = true;
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nearfield::layout::{cameras, Layout};
    use crate::nearfield::rayset::{CaptureSphere, Intrinsics};
    use glam::DVec2;

    fn set_of(layout: Layout) -> RayImageSet {
        let sphere = CaptureSphere {
            centre_m: DVec3::ZERO,
            radius_m: 1.0,
        };
        RayImageSet {
            sphere,
            intrinsics: Intrinsics {
                width: 8,
                height: 8,
                principal_px: DVec2::splat(4.0),
                focal_px: DVec2::splat(8.0),
            },
            cameras: cameras(&sphere, &layout, 1).unwrap(),
        }
    }

    #[test]
    fn kd_tree_matches_brute_force() {
        let dirs: Vec<DVec3> = (0..2000).map(|i| fibonacci(i * 7 % 2000, 2000)).collect();
        let index = CameraIndex::new(&dirs);
        for j in 0..300 {
            let q = fibonacci(j, 300).normalize();
            let (i, a) = index.nearest(q).unwrap();
            let brute = dirs
                .iter()
                .map(|d| d.dot(q).clamp(-1.0, 1.0).acos())
                .fold(f64::INFINITY, f64::min);
            assert!((a - brute).abs() < 1e-9, "{a} vs {brute}");
            assert!((dirs[i].dot(q).clamp(-1.0, 1.0).acos() - brute).abs() < 1e-9);
            let k = index.k_nearest(q, 5);
            assert_eq!(k.len(), 5);
            assert!(k.windows(2).all(|w| w[0].1 <= w[1].1));
        }
    }

    #[test]
    fn one_hemisphere_leaves_a_90_degree_gap() {
        // A grid whose rows stop at the equator: the zenith is 90° from every camera.
        let mut set = set_of(Layout::Grid {
            phi_steps: 36,
            theta_steps: 37,
        });
        set.cameras.retain(|c| c.position_m.z <= 1e-9);
        let cov = Coverage::new(&set);
        assert!((cov.stats.max_gap_deg - 90.0).abs() < 0.05, "{:?}", cov.stats);
        assert!(cov.stats.max_gap_at_deg[1] > 179.0, "{:?}", cov.stats);
        assert_eq!(cov.stats.upper, 0);
    }

    #[test]
    fn fibonacci_gap_is_small_and_the_picture_renders() {
        let set = set_of(Layout::Fibonacci { count: 4000 });
        let cov = Coverage::new(&set);
        // Mean spacing √(4π/4000) ≈ 3.2°; gaps are about half of it.
        assert!(
            cov.stats.max_gap_deg < 3.0 && cov.stats.median_gap_deg > 0.5,
            "{:?}",
            cov.stats
        );
        assert!(cov.stats.median_gap_deg < cov.stats.p95_gap_deg);
        let png = cov.to_png(800).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        assert!(cov.to_png(100).is_err());
    }
}

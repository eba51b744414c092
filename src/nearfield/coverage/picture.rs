//! The coverage picture (`lumiview cameras`): left, the camera positions on two Lambert equal-area
//! discs (lower hemisphere seen from below, upper seen from above, each to 100° from its pole so
//! the overlap at the equator shows), cameras coloured by hemisphere; right, an equirectangular
//! map (φ across, θ up: zenith at the top) of the angle to the nearest camera, with a colour bar.

use glam::DVec3;
use tiny_skia::{Color, FillRule, Paint, PathBuilder, Pixmap, Rect, Stroke, StrokeDash, Transform};

use super::Coverage;
use crate::draw::colormap::VIRIDIS;
use crate::draw::text::{Anchor, Typeface, FONT_PATH};
use crate::draw::ticks::{label_at_step, step_at_least};
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::Hemisphere;

/// Smallest accepted picture width, pixels.
pub const MIN_WIDTH_PX: u32 = 640;

/// Largest accepted picture width, pixels.
pub const MAX_WIDTH_PX: u32 = 8192;

impl Coverage {
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

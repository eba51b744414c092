//! The work-plane grid as a lighting designer reads it: a plan view in false colour with isolux
//! lines, the luminaires marked, and the figures a lighting report gives (Ē, Emin, Emax,
//! U0 = Emin/Ē, Emin/Emax).
//!
//! Promises:
//! - Plan view from above: scene +X to the right, +Z down (so +Y, up, points at the reader), equal
//!   scale on both axes, axes ticked in metres at a 1-2-5 step.
//! - Each grid cell is filled with the colour of its illuminance band; the bands lie between
//!   consecutive isolux levels, taken from the maintained-illuminance scale of EN 12464-1
//!   (… 20, 30, 50, 75, 100, 150, 200, 300, 500, 750, 1000 … lx) within the grid's range, at most
//!   [`MAX_LEVELS`] of them (every second value when there are more). A colour bar labelled in lx
//!   sits at the right.
//! - Isolux lines (marching squares over the cell centres, `photometry::contour`) in dark grey,
//!   each long enough to carry it labelled with its value on a white box.
//! - Luminaires (their photometric centres projected on the plane) as white circles with a cross;
//!   the minimum and maximum as a blue ○ and a red ×.
//! - Figures from [`GridStats`]; the caption states the plane, grid, method and units.

use tiny_skia::{FillRule, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform};

use super::error::{Result, SceneError};
use super::grid::FloorRect;
use crate::draw::colormap::YELLOW_ORANGE_BROWN;
use crate::draw::text::{Anchor, Typeface};
use crate::draw::ticks::{label_at_step, step_for_span};
use crate::photometry::contour::contour_lines;
use crate::photometry::isolux::{decimal, fmt_significant};

/// Most isolux levels drawn.
pub const MAX_LEVELS: usize = 9;

/// The figures of a calculation surface, lx.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridStats {
    /// Smallest illuminance.
    pub min_lx: f64,
    /// Mean illuminance Ē (every point weighs the same: the cells are equal).
    pub avg_lx: f64,
    /// Largest illuminance.
    pub max_lx: f64,
    /// Uniformity U0 = Emin/Ē (0 when Ē is 0).
    pub u0: f64,
    /// Emin/Emax (0 when Emax is 0).
    pub min_over_max: f64,
    /// Index of the smallest value.
    pub argmin: usize,
    /// Index of the largest value.
    pub argmax: usize,
}

impl GridStats {
    /// The figures of `values_lx`.
    ///
    /// Errors (argument `values_lx`): empty, or a value that is not finite.
    pub fn of(values_lx: &[f64]) -> Result<Self> {
        if values_lx.is_empty() {
            return Err(SceneError::invalid("values_lx", "no values"));
        }
        if let Some(i) = values_lx.iter().position(|v| !v.is_finite()) {
            return Err(SceneError::invalid(
                "values_lx",
                format!("value {i} is {}, not a finite illuminance", values_lx[i]),
            ));
        }
        let (mut argmin, mut argmax) = (0, 0);
        for (i, &v) in values_lx.iter().enumerate() {
            if v < values_lx[argmin] {
                argmin = i;
            }
            if v > values_lx[argmax] {
                argmax = i;
            }
        }
        let (min_lx, max_lx) = (values_lx[argmin], values_lx[argmax]);
        let avg_lx = values_lx.iter().sum::<f64>() / values_lx.len() as f64;
        Ok(GridStats {
            min_lx,
            avg_lx,
            max_lx,
            u0: if avg_lx > 0.0 { min_lx / avg_lx } else { 0.0 },
            min_over_max: if max_lx > 0.0 { min_lx / max_lx } else { 0.0 },
            argmin,
            argmax,
        })
    }
}

/// The isolux levels of a grid from `min_lx` to `max_lx`: the EN 12464-1 scale values strictly
/// between them (1, 1.5, 2, 3, 5, 7.5 × 10ⁿ lx), thinned to every second one while there are more
/// than [`MAX_LEVELS`]. Empty when `max_lx` is not finite and > 0.
pub fn grid_levels(min_lx: f64, max_lx: f64) -> Vec<f64> {
    if !(max_lx.is_finite() && max_lx > 0.0) {
        return Vec::new();
    }
    let lo = if min_lx.is_finite() && min_lx > 0.0 {
        min_lx
    } else {
        max_lx * 1e-3
    };
    let mut levels = Vec::new();
    let mut e = lo.log10().floor() as i32 - 1;
    while 10f64.powi(e) < max_lx {
        for m in [1.0, 1.5, 2.0, 3.0, 5.0, 7.5] {
            let v = decimal(m, e);
            if v > lo && v < max_lx {
                levels.push(v);
            }
        }
        e += 1;
    }
    while levels.len() > MAX_LEVELS {
        levels = levels.into_iter().step_by(2).collect();
    }
    levels
}

/// What a grid plot shows.
#[derive(Debug, Clone)]
pub struct GridPlot<'a> {
    /// The rectangle the grid covers, scene metres.
    pub rect: FloorRect,
    /// Cells along X.
    pub nx: usize,
    /// Cells along Z.
    pub nz: usize,
    /// Illuminance at each cell centre, lx, X fastest (the order of `work_plane_grid`).
    pub values_lx: &'a [f64],
    /// Luminaire positions projected on the plane: (x, z) in scene metres.
    pub luminaires_xz_m: &'a [[f64; 2]],
    /// Title line.
    pub title: String,
    /// Caption lines (plane, grid, method).
    pub caption: Vec<String>,
    /// Image width, pixels (400…4000).
    pub width_px: u32,
}

const INK: [u8; 4] = [30, 30, 30, 255];
const LINE: [u8; 4] = [60, 60, 60, 255];

fn paint(c: [u8; 4]) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color_rgba8(c[0], c[1], c[2], c[3]);
    p.anti_alias = true;
    p
}

fn stroke(width: f32) -> Stroke {
    Stroke {
        width,
        ..Stroke::default()
    }
}

fn rect(x: f64, y: f64, w: f64, h: f64) -> Option<Rect> {
    Rect::from_xywh(x as f32, y as f32, w as f32, h as f32)
}

/// A value in lx as written on lines and the bar (3 significant digits, no trailing zeros).
pub fn fmt_lx(v: f64) -> String {
    fmt_significant(v, 3)
}

impl GridPlot<'_> {
    /// The plot as an opaque RGBA pixmap.
    ///
    /// Errors: a width outside 400…4000 px (argument `width_px`); `values_lx` not `nx × nz` long or
    /// not finite (argument `values_lx`); a rectangle without area (argument `rect`); the bundled
    /// font unreadable or the pixmap not allocatable (argument `plot`).
    pub fn to_pixmap(&self) -> Result<Pixmap> {
        if !(400..=4000).contains(&self.width_px) {
            return Err(SceneError::invalid(
                "width_px",
                format!("{} px: expected 400…4000", self.width_px),
            ));
        }
        if self.nx < 1 || self.nz < 1 || self.values_lx.len() != self.nx * self.nz {
            return Err(SceneError::invalid(
                "values_lx",
                format!("{} values for {} × {} cells", self.values_lx.len(), self.nx, self.nz),
            ));
        }
        let stats = GridStats::of(self.values_lx)?;
        let r = self.rect;
        let (wm, dm) = (r.x_max_m - r.x_min_m, r.z_max_m - r.z_min_m);
        if !(wm.is_finite() && dm.is_finite() && wm > 0.0 && dm > 0.0) {
            return Err(SceneError::invalid("rect", format!("{r:?} has no area")));
        }
        let face = Typeface::load().map_err(|e| SceneError::invalid("plot", e))?;
        let w = f64::from(self.width_px);
        let s = w / 900.0; // text and line scale
        let margin = 24.0 * s;
        let bar_w = 110.0 * s;
        let title_h = 56.0 * s;
        let axis_h = 40.0 * s;
        let axis_w = 52.0 * s;
        // Plot area: as wide as the page allows, the height from the rectangle's aspect.
        let area_w = w - 2.0 * margin - axis_w - bar_w;
        let scale = (area_w / wm).min(area_w * 0.9 / dm); // px per metre
        let (aw, ah) = (wm * scale, dm * scale);
        let ax = margin + axis_w;
        let ay = margin + title_h;
        let caption_size = 14.0 * s;
        let row = 21.0 * s;
        let lines_below = 2 + self.caption.len();
        let h = (ay + ah + axis_h + row * lines_below as f64 + margin).ceil();
        let mut pm = Pixmap::new(self.width_px, h as u32)
            .ok_or_else(|| SceneError::invalid("plot", format!("cannot allocate {} × {h} px", self.width_px)))?;
        pm.fill(tiny_skia::Color::WHITE);
        let to_px = |x_m: f64, z_m: f64| (ax + (x_m - r.x_min_m) * scale, ay + (z_m - r.z_min_m) * scale);

        // Title.
        let (t, ts) = face.fit(&self.title, 19.0 * s, w - 2.0 * margin);
        face.text(&mut pm, &t, margin, margin + 22.0 * s, ts, INK, Anchor::Start);

        // Fill: each pixel in the band of the illuminance interpolated bilinearly between the
        // cell centres (as the isolux lines are), held constant beyond the outer centres.
        let levels = grid_levels(stats.min_lx, stats.max_lx);
        let bands = levels.len() + 1;
        let band_of = |v: f64| levels.iter().take_while(|&&l| v >= l).count();
        let colour = |b: usize| {
            let c = YELLOW_ORANGE_BROWN.class(b, bands);
            [c[0], c[1], c[2], 255]
        };
        let (cw, ch) = (aw / self.nx as f64, ah / self.nz as f64);
        let value_at = |gx: f64, gz: f64| {
            let gx = gx.clamp(0.0, (self.nx - 1) as f64);
            let gz = gz.clamp(0.0, (self.nz - 1) as f64);
            let (i0, k0) = (gx.floor() as usize, gz.floor() as usize);
            let (i1, k1) = ((i0 + 1).min(self.nx - 1), (k0 + 1).min(self.nz - 1));
            let (fx, fz) = (gx - i0 as f64, gz - k0 as f64);
            let v = |i: usize, k: usize| self.values_lx[k * self.nx + i];
            (v(i0, k0) * (1.0 - fx) + v(i1, k0) * fx) * (1.0 - fz) + (v(i0, k1) * (1.0 - fx) + v(i1, k1) * fx) * fz
        };
        {
            let (x0, y0) = (ax.round() as u32, ay.round() as u32);
            let (x1, y1) = ((ax + aw).round() as u32, (ay + ah).round() as u32);
            let width = pm.width();
            let data = pm.data_mut();
            for py in y0..y1 {
                for px in x0..x1 {
                    let gx = (f64::from(px) + 0.5 - ax) / cw - 0.5;
                    let gz = (f64::from(py) + 0.5 - ay) / ch - 0.5;
                    let c = colour(band_of(value_at(gx, gz)));
                    let o = 4 * (py as usize * width as usize + px as usize);
                    if let Some(d) = data.get_mut(o..o + 4) {
                        d.copy_from_slice(&c);
                    }
                }
            }
        }

        // Isolux lines and their labels.
        let grid_to_px = |gx: f64, gz: f64| (ax + (gx + 0.5) * cw, ay + (gz + 0.5) * ch);
        let mut boxes: Vec<[f64; 4]> = Vec::new();
        let label_size = 12.0 * s;
        for &level in &levels {
            for line in contour_lines(self.values_lx, self.nx, self.nz, level) {
                let pts: Vec<(f64, f64)> = line.points.iter().map(|p| grid_to_px(p[0], p[1])).collect();
                let mut pb = PathBuilder::new();
                for (j, &(x, y)) in pts.iter().enumerate() {
                    if j == 0 {
                        pb.move_to(x as f32, y as f32);
                    } else {
                        pb.line_to(x as f32, y as f32);
                    }
                }
                if line.closed {
                    pb.close();
                }
                if let Some(path) = pb.finish() {
                    pm.stroke_path(
                        &path,
                        &paint(LINE),
                        &stroke((1.3 * s) as f32),
                        Transform::identity(),
                        None,
                    );
                }
                // A label at the point half-way along a line long enough to carry it, unless it
                // would cover another label.
                let len: f64 = pts.windows(2).map(|p| (p[1].0 - p[0].0).hypot(p[1].1 - p[0].1)).sum();
                let text = fmt_lx(level);
                let tw = face.width(&text, label_size) + 6.0 * s;
                if len < 3.0 * tw {
                    continue;
                }
                let mut walked = 0.0;
                let mut at = pts[0];
                for p in pts.windows(2) {
                    let d = (p[1].0 - p[0].0).hypot(p[1].1 - p[0].1);
                    if walked + d >= len / 2.0 {
                        let t = if d > 0.0 { (len / 2.0 - walked) / d } else { 0.0 };
                        at = (p[0].0 + t * (p[1].0 - p[0].0), p[0].1 + t * (p[1].1 - p[0].1));
                        break;
                    }
                    walked += d;
                }
                let bh = label_size * 1.3;
                let b = [at.0 - tw / 2.0, at.1 - bh / 2.0, tw, bh];
                let overlaps = boxes
                    .iter()
                    .any(|o| b[0] < o[0] + o[2] && o[0] < b[0] + b[2] && b[1] < o[1] + o[3] && o[1] < b[1] + b[3]);
                if overlaps {
                    continue;
                }
                boxes.push(b);
                if let Some(rc) = rect(b[0], b[1], b[2], b[3]) {
                    pm.fill_rect(rc, &paint([255, 255, 255, 235]), Transform::identity(), None);
                }
                face.text(
                    &mut pm,
                    &text,
                    at.0,
                    at.1 + label_size * 0.36,
                    label_size,
                    INK,
                    Anchor::Middle,
                );
            }
        }

        // Luminaires, minimum and maximum.
        let rad = 6.0 * s;
        for &[x, z] in self.luminaires_xz_m {
            let (px, py) = to_px(x, z);
            if let Some(c) = PathBuilder::from_circle(px as f32, py as f32, rad as f32) {
                pm.fill_path(
                    &c,
                    &paint([255, 255, 255, 255]),
                    FillRule::Winding,
                    Transform::identity(),
                    None,
                );
                pm.stroke_path(&c, &paint(INK), &stroke((1.5 * s) as f32), Transform::identity(), None);
            }
            cross(&mut pm, px, py, rad * 0.7, INK, 1.2 * s);
        }
        let centre = |idx: usize| {
            let (i, k) = (idx % self.nx, idx / self.nx);
            grid_to_px(i as f64, k as f64)
        };
        let (mx, my) = centre(stats.argmax);
        cross(&mut pm, mx, my, 6.0 * s, [210, 20, 20, 255], 2.5 * s);
        let (nx_, ny_) = centre(stats.argmin);
        if let Some(c) = PathBuilder::from_circle(nx_ as f32, ny_ as f32, (6.0 * s) as f32) {
            pm.stroke_path(
                &c,
                &paint([20, 60, 210, 255]),
                &stroke((2.5 * s) as f32),
                Transform::identity(),
                None,
            );
        }

        // Frame and axes in metres.
        if let Some(rc) = rect(ax, ay, aw, ah) {
            let path = PathBuilder::from_rect(rc);
            pm.stroke_path(
                &path,
                &paint(INK),
                &stroke((1.2 * s) as f32),
                Transform::identity(),
                None,
            );
        }
        let tick = 5.0 * s;
        let tsize = 12.0 * s;
        let step = step_for_span(wm.max(dm), 10.0);
        let ticks = |lo: f64, hi: f64| {
            let mut v = (lo / step).ceil() * step;
            let mut out = Vec::new();
            while v <= hi + 1e-9 * step {
                out.push(if v.abs() < 1e-9 * step { 0.0 } else { v });
                v += step;
            }
            out
        };
        for x in ticks(r.x_min_m, r.x_max_m) {
            let (px, _) = to_px(x, r.z_min_m);
            line(&mut pm, px, ay + ah, px, ay + ah + tick, INK, s);
            face.text(
                &mut pm,
                &label_at_step(x, step),
                px,
                ay + ah + tick + tsize,
                tsize,
                INK,
                Anchor::Middle,
            );
        }
        for z in ticks(r.z_min_m, r.z_max_m) {
            let (_, py) = to_px(r.x_min_m, z);
            line(&mut pm, ax - tick, py, ax, py, INK, s);
            face.text(
                &mut pm,
                &label_at_step(z, step),
                ax - tick - 3.0 * s,
                py + tsize * 0.36,
                tsize,
                INK,
                Anchor::End,
            );
        }
        face.text(
            &mut pm,
            "x (m) →",
            ax + aw,
            ay + ah + tick + 2.2 * tsize,
            tsize,
            INK,
            Anchor::End,
        );
        face.text(&mut pm, "z (m) ↓", margin, ay - 8.0 * s, tsize, INK, Anchor::Start);

        // Colour bar: one box per band, labelled at the levels.
        let bx = ax + aw + 26.0 * s;
        let bw = 22.0 * s;
        let bh = (ah / bands as f64).min(40.0 * s);
        let by = ay + (ah - bh * bands as f64) / 2.0;
        for b in 0..bands {
            // Highest band on top.
            let y = by + (bands - 1 - b) as f64 * bh;
            if let Some(rc) = rect(bx, y, bw, bh) {
                pm.fill_rect(rc, &paint(colour(b)), Transform::identity(), None);
                pm.stroke_path(
                    &PathBuilder::from_rect(rc),
                    &paint(INK),
                    &stroke((0.8 * s) as f32),
                    Transform::identity(),
                    None,
                );
            }
        }
        for (j, &l) in levels.iter().enumerate() {
            let y = by + (bands - 1 - j) as f64 * bh;
            face.text(
                &mut pm,
                &fmt_lx(l),
                bx + bw + 5.0 * s,
                y + tsize * 0.36,
                tsize,
                INK,
                Anchor::Start,
            );
        }
        face.text(&mut pm, "E (lx)", bx, by - 8.0 * s, tsize, INK, Anchor::Start);

        // Figures and caption.
        let mut y = ay + ah + axis_h + row;
        let figures = format!(
            "Ē {} lx    Emin {} lx (○)    Emax {} lx (×)    U0 = Emin/Ē {:.2}    Emin/Emax {:.2}",
            fmt_lx(stats.avg_lx),
            fmt_lx(stats.min_lx),
            fmt_lx(stats.max_lx),
            stats.u0,
            stats.min_over_max
        );
        let (t, fs) = face.fit(&figures, 16.0 * s, w - 2.0 * margin);
        face.text(&mut pm, &t, margin, y, fs, INK, Anchor::Start);
        y += row * 1.2;
        for c in &self.caption {
            let (t, cs) = face.fit(c, caption_size, w - 2.0 * margin);
            face.text(&mut pm, &t, margin, y, cs, [70, 70, 70, 255], Anchor::Start);
            y += row;
        }
        Ok(pm)
    }
}

fn line(pm: &mut Pixmap, x0: f64, y0: f64, x1: f64, y1: f64, c: [u8; 4], width: f64) {
    let mut pb = PathBuilder::new();
    pb.move_to(x0 as f32, y0 as f32);
    pb.line_to(x1 as f32, y1 as f32);
    if let Some(p) = pb.finish() {
        pm.stroke_path(&p, &paint(c), &stroke(width as f32), Transform::identity(), None);
    }
}

fn cross(pm: &mut Pixmap, x: f64, y: f64, r: f64, c: [u8; 4], width: f64) {
    line(pm, x - r, y - r, x + r, y + r, c, width);
    line(pm, x - r, y + r, x + r, y - r, c, width);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_are_the_report_figures() {
        let s = GridStats::of(&[100.0, 300.0, 200.0, 400.0]).unwrap();
        assert_eq!((s.min_lx, s.avg_lx, s.max_lx), (100.0, 250.0, 400.0));
        assert_eq!((s.u0, s.min_over_max), (0.4, 0.25));
        assert_eq!((s.argmin, s.argmax), (0, 3));
        assert!(GridStats::of(&[]).is_err());
        let e = GridStats::of(&[1.0, f64::NAN]).unwrap_err().to_string();
        assert!(e.contains("value 1"), "{e}");
    }

    #[test]
    fn levels_follow_the_en_12464_scale() {
        assert_eq!(grid_levels(180.0, 820.0), vec![200.0, 300.0, 500.0, 750.0]);
        assert_eq!(grid_levels(0.0, 0.0), Vec::<f64>::new());
        let wide = grid_levels(0.5, 5000.0);
        assert!(wide.len() <= MAX_LEVELS && wide.len() >= 5, "{wide:?}");
        assert!(wide.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(fmt_lx(0.3), "0.3");
        assert_eq!(fmt_lx(512.4), "512");
        assert_eq!(fmt_lx(7.5), "7.5");
    }

    #[test]
    fn a_plot_has_its_bands_and_refuses_bad_input() {
        let (nx, nz) = (30, 20);
        let values: Vec<f64> = (0..nx * nz)
            .map(|i| {
                let (x, z) = ((i % nx) as f64 - 15.0, (i / nx) as f64 - 10.0);
                800.0 * (-(x * x + z * z) / 120.0).exp()
            })
            .collect();
        let plot = GridPlot {
            rect: FloorRect {
                x_min_m: -3.0,
                x_max_m: 3.0,
                z_min_m: -2.0,
                z_max_m: 2.0,
            },
            nx,
            nz,
            values_lx: &values,
            luminaires_xz_m: &[[0.0, 0.0]],
            title: "test".into(),
            caption: vec!["caption".into()],
            width_px: 600,
        };
        let pm = plot.to_pixmap().unwrap();
        assert_eq!(pm.width(), 600);
        // The darkest band's colour appears (the centre is above the top level).
        let top = YELLOW_ORANGE_BROWN.class(grid_levels(0.0, 800.0).len(), grid_levels(0.0, 800.0).len() + 1);
        assert!(pm.pixels().iter().any(|p| [p.red(), p.green(), p.blue()] == top));
        let bad = GridPlot {
            values_lx: &values[1..],
            ..plot.clone()
        };
        assert!(bad.to_pixmap().unwrap_err().to_string().contains("values_lx"));
        let narrow = GridPlot { width_px: 10, ..plot };
        assert!(narrow.to_pixmap().is_err());
    }
}

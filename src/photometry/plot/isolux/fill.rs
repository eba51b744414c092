//! The false-colour fill of the isolux diagram: each band between consecutive levels in one colour
//! of the fill's colour map, nothing below the lowest level, and the colour bar that labels the
//! bands in lx.

use super::page::{fmt_level, Page, BAR_HEADER};
use crate::draw::colormap::YELLOW_ORANGE_BROWN;
use crate::photometry::isolux::IsoluxGrid;
use crate::photometry::plot::layout::Bounds;
use crate::photometry::plot::scene::{RasterImage, Rgba, Scene, Shape, TextAnchor, INK};
use crate::photometry::plot::{PlotError, CAP_HEIGHT};

/// The colour of band `i` of `n` (band 0 lies between the two lowest levels): the fill's colour map
/// ([`YELLOW_ORANGE_BROWN`]: light, so the dark lines and their white labels stay readable on every
/// band) spread over the bands.
fn band_colour(i: usize, n: usize) -> Rgba {
    let [r, g, b] = YELLOW_ORANGE_BROWN.class(i, n);
    Rgba([r, g, b, 255])
}

/// The false-colour fill of the square, one image pixel per page pixel: E interpolated bilinearly
/// from the grid, coloured by its band; transparent below the lowest level.
pub(super) fn fill_image(grid: &IsoluxGrid, page: &Page, levels: &[f64]) -> Result<RasterImage, PlotError> {
    let side = (page.area.max[0] - page.area.min[0]) as u32;
    let n = grid.points_per_side();
    let k = grid.half_points as f64;
    let hw = grid.half_width_m();
    let colours: Vec<Rgba> = (0..levels.len()).map(|i| band_colour(i, levels.len())).collect();
    let sample = |g: f64| {
        let g = g.clamp(0.0, (n - 1) as f64);
        let i = (g.floor() as usize).min(n - 2);
        (i, g - i as f64)
    };
    let mut rgba = vec![0u8; side as usize * side as usize * 4];
    for (j, row) in rgba.chunks_mut(side as usize * 4).enumerate() {
        let y_m = hw - (j as f64 + 0.5) / f64::from(side) * 2.0 * hw;
        let (iy, fy) = sample(y_m / grid.step_m + k);
        for (i, px) in row.chunks_mut(4).enumerate() {
            let x_m = -hw + (i as f64 + 0.5) / f64::from(side) * 2.0 * hw;
            let (ix, fx) = sample(x_m / grid.step_m + k);
            let at = |a: usize, b: usize| grid.e_lx[(iy + b) * n + ix + a];
            let e = (at(0, 0) * (1.0 - fx) + at(1, 0) * fx) * (1.0 - fy) + (at(0, 1) * (1.0 - fx) + at(1, 1) * fx) * fy;
            let band = levels.iter().filter(|&&l| e >= l).count();
            if band > 0 {
                px.copy_from_slice(&colours[band - 1].0);
            }
        }
    }
    RasterImage::new([page.area.min[0] as u32, page.area.min[1] as u32], side, side, rgba)
}

/// One swatch per band, lowest at the bottom, the levels at the band boundaries, the unit above.
pub(super) fn draw_colour_bar(scene: &mut Scene, page: &Page, bar: Bounds, levels: &[f64]) {
    let n = levels.len();
    let band_h = (bar.max[1] - bar.min[1]) / n as f64;
    for i in 0..n {
        let bottom = bar.max[1] - band_h * i as f64;
        scene.push(
            "colour-bar",
            Shape::Rect {
                min: [bar.min[0], bottom - band_h],
                max: [bar.max[0], bottom],
                fill: band_colour(i, n),
            },
        );
    }
    scene.push(
        "colour-bar",
        Shape::Polyline {
            points: vec![bar.min, [bar.max[0], bar.min[1]], bar.max, [bar.min[0], bar.max[1]]],
            closed: true,
            stroke: page.stroke(0.8, Rgba::grey(110)),
        },
    );
    for (i, &level) in levels.iter().enumerate() {
        let y = bar.max[1] - band_h * i as f64;
        scene.push(
            "colour-bar",
            Shape::Line {
                from: [bar.max[0], y],
                to: [bar.max[0] + 4.0 * page.text, y],
                stroke: page.stroke(0.8, Rgba::grey(110)),
            },
        );
        scene.text(
            "colour-bar",
            [bar.max[0] + 6.0 * page.text, y + CAP_HEIGHT * page.tick_size / 2.0],
            page.tick_size,
            TextAnchor::Start,
            INK,
            fmt_level(level),
        );
    }
    scene.text(
        "colour-bar",
        [bar.min[0], page.axis_title_baseline],
        page.axis_size,
        TextAnchor::Start,
        INK,
        BAR_HEADER.to_string(),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_span_the_colour_map() {
        let stops = YELLOW_ORANGE_BROWN.stops();
        assert_eq!(band_colour(0, 6).0[..3], stops[0]);
        assert_eq!(band_colour(5, 6).0[..3], stops[5]);
        assert_eq!(band_colour(0, 1).0[..3], stops[0]);
    }
}

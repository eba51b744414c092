//! Where one capture image holds light, stored small enough to keep a thousand of them: the lit
//! pixels as runs per row (exact, for small footprints) and a chessboard distance map over
//! `COARSE_PX`-pixel cells (for large ones). Both answer one question conservatively: "is every pixel
//! of this square dark?" A square is called dark only when it certainly is.

use crate::nearfield::rayset::LuminanceImage;

/// Edge of a coarse cell (px).
pub const COARSE_PX: u32 = 8;

/// Squares with more rows than this are answered from the coarse map.
const EXACT_ROWS: i64 = 24;

/// Coarse cells kept around the lit ones in the distance map (beyond them the distance to the lit
/// cells' box is used; the coarse map answers squares of at least [`EXACT_ROWS`] rows, 3 cells).
const DIST_MARGIN: u32 = 8;

/// The lit pixels of one image.
#[derive(Debug, Clone)]
pub struct LitMask {
    width: u32,
    height: u32,
    /// First row that may hold a lit run (the rows above hold none).
    row0: u32,
    /// Index into `runs` of the first run of each row from `row0` on, and one past the last
    /// (the rows below hold none): only the lit rows are stored, so a small source's mask is small.
    row_start: Vec<u32>,
    /// Lit runs `[start, end)` (columns), row by row, left to right.
    runs: Vec<(u16, u16)>,
    /// Coarse cells across and down.
    cw: u32,
    ch: u32,
    /// The coarse cells holding a lit pixel: `[x0, x1, y0, y1]`, inclusive (`None`: none).
    lit_cells: Option<[u32; 4]>,
    /// `[x0, y0, width, height]` (cells): the lit cells' box grown by [`DIST_MARGIN`] cells, clipped
    /// to the image; `dist` covers it.
    window: [u32; 4],
    /// Chessboard distance (cells, saturating at 255) from each coarse cell of `window` to the
    /// nearest cell holding a lit pixel (0: the cell holds one). Outside the window the distance to
    /// the lit cells' box stands in (never more than the true distance, so dark stays certain).
    dist: Vec<u8>,
    /// Lit pixels.
    pub lit_pixels: u64,
    /// Largest luminance in the image (cd/m²).
    pub max_cd_m2: f32,
    /// Least luminance of a lit pixel (cd/m²; 0 for an image with none).
    pub floor_cd_m2: f32,
}

impl LitMask {
    /// The pixels of `img` at or above `relative · max` (and above 0), where max is the image's
    /// largest value (every pixel dark when that is 0); `None` when the image is wider than 65535 px.
    pub fn of(img: &LuminanceImage, relative: f32) -> Option<Self> {
        let max = largest(img);
        Self::above(img, max, relative * max)
    }

    /// The pixels of `img` at or above `relative · max` and at or above [`NOISE_SIGMAS`] times the
    /// image's noise ([`noise_sigma`]): for a `relative` far below what [`Self::of`] is given, as
    /// deep as the image's own noise lets a mask go. `None` as for [`Self::of`].
    pub fn above_noise(img: &LuminanceImage, relative: f32) -> Option<Self> {
        Self::above_noise_with(img, relative, noise_sigma(img))
    }

    /// [`Self::above_noise`] with the image's noise given (one standard deviation, cd/m², as
    /// [`noise_sigma`] gives it).
    pub fn above_noise_with(img: &LuminanceImage, relative: f32, sigma: f32) -> Option<Self> {
        let max = largest(img);
        Self::above(img, max, noise_floor(max, relative, sigma))
    }

    /// How many pixels [`Self::above_noise_with`] lights (`None` as it gives), without making the
    /// mask.
    pub fn count_above_noise_with(img: &LuminanceImage, relative: f32, sigma: f32) -> Option<u64> {
        if img.width > u32::from(u16::MAX) {
            return None;
        }
        let max = largest(img);
        if max <= 0.0 {
            return Some(0);
        }
        let floor = noise_floor(max, relative, sigma).max(f32::MIN_POSITIVE);
        Some(img.data.iter().filter(|v| **v >= floor).count() as u64)
    }

    /// The pixels of `img` at or above `floor` (and above 0); `max`: its largest value.
    fn above(img: &LuminanceImage, max: f32, floor: f32) -> Option<Self> {
        let (w, h) = (img.width, img.height);
        if w > u32::from(u16::MAX) {
            return None;
        }
        if max <= 0.0 {
            return Some(Self::unlit(w, h));
        }
        let floor = floor.max(f32::MIN_POSITIVE);
        let (cw, ch) = (w.div_ceil(COARSE_PX), h.div_ceil(COARSE_PX));
        // Every row's first run (`height + 1` entries), trimmed to the lit rows below.
        let mut row_start = Vec::with_capacity(h as usize + 1);
        let mut runs = Vec::new();
        let mut lit_pixels = 0u64;
        let (mut x0, mut x1, mut y0, mut y1) = (u32::MAX, 0u32, u32::MAX, 0u32);
        for r in 0..h {
            row_start.push(runs.len() as u32);
            let row = &img.data[(r * w) as usize..((r + 1) * w) as usize];
            let mut c = 0usize;
            while c < row.len() {
                if row[c] >= floor {
                    let s = c;
                    while c < row.len() && row[c] >= floor {
                        c += 1;
                    }
                    runs.push((s as u16, c as u16));
                    lit_pixels += (c - s) as u64;
                    (x0, x1) = (x0.min(s as u32 / COARSE_PX), x1.max((c as u32 - 1) / COARSE_PX));
                    (y0, y1) = (y0.min(r / COARSE_PX), y1.max(r / COARSE_PX));
                } else {
                    c += 1;
                }
            }
        }
        row_start.push(runs.len() as u32);
        if runs.is_empty() {
            let mut m = Self::unlit(w, h);
            m.max_cd_m2 = max;
            m.floor_cd_m2 = floor;
            return Some(m);
        }
        // Rows before the first lit one and after the last hold no run.
        let first = row_start.iter().position(|&k| k > 0).map_or(0, |k| k - 1);
        let last = row_start
            .iter()
            .position(|&k| k as usize == runs.len())
            .unwrap_or(h as usize);
        let row_start: Vec<u32> = row_start[first..=last].to_vec();
        runs.shrink_to_fit();
        let (wx, wy) = (x0.saturating_sub(DIST_MARGIN), y0.saturating_sub(DIST_MARGIN));
        let window = [
            wx,
            wy,
            (x1 + DIST_MARGIN).min(cw - 1) + 1 - wx,
            (y1 + DIST_MARGIN).min(ch - 1) + 1 - wy,
        ];
        let mut lit_cells = vec![false; (window[2] * window[3]) as usize];
        for (i, r) in (first as u32..).zip(row_start.windows(2)) {
            for &(s, e) in &runs[r[0] as usize..r[1] as usize] {
                let cy = i / COARSE_PX - window[1];
                for cx in (u32::from(s) / COARSE_PX)..=((u32::from(e) - 1) / COARSE_PX) {
                    lit_cells[(cy * window[2] + cx - window[0]) as usize] = true;
                }
            }
        }
        Some(Self {
            width: w,
            height: h,
            row0: first as u32,
            row_start,
            runs,
            cw,
            ch,
            lit_cells: Some([x0, x1, y0, y1]),
            window,
            dist: chessboard(&lit_cells, window[2] as usize, window[3] as usize),
            lit_pixels,
            max_cd_m2: max,
            floor_cd_m2: floor,
        })
    }

    /// A `width` × `height` image with no lit pixel (a camera that sees no light: every square is
    /// dark).
    pub fn unlit(width: u32, height: u32) -> Self {
        let (cw, ch) = (width.div_ceil(COARSE_PX), height.div_ceil(COARSE_PX));
        Self {
            width,
            height,
            row0: 0,
            row_start: vec![0],
            runs: Vec::new(),
            cw,
            ch,
            lit_cells: None,
            window: [0; 4],
            dist: Vec::new(),
            lit_pixels: 0,
            max_cd_m2: 0.0,
            floor_cd_m2: 0.0,
        }
    }

    /// Image width and height (px).
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The lit pixels' bounding box `[col0, col1, row0, row1]` (pixel edges, px).
    pub fn lit_box(&self) -> Option<[f64; 4]> {
        let rows: Vec<usize> = (0..self.height as usize).filter(|&r| !self.row(r).is_empty()).collect();
        let (first, last) = (*rows.first()?, *rows.last()?);
        let (mut c0, mut c1) = (u16::MAX, 0u16);
        for &(s, e) in &self.runs {
            c0 = c0.min(s);
            c1 = c1.max(e);
        }
        Some([f64::from(c0), f64::from(c1), first as f64, (last + 1) as f64])
    }

    /// Centres (pixel coordinates) of up to `max` lit pixels, spread evenly over them in raster
    /// order.
    pub fn lit_centres(&self, max: usize) -> Vec<(f64, f64)> {
        let step = (self.lit_pixels as usize).div_ceil(max.max(1)).max(1);
        let mut out = Vec::new();
        let mut k = 0usize;
        for r in 0..self.height as usize {
            for &(s, e) in self.row(r) {
                for c in s..e {
                    if k.is_multiple_of(step) {
                        out.push((f64::from(c) + 0.5, r as f64 + 0.5));
                    }
                    k += 1;
                }
            }
        }
        out
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.row_start.len() * 4 + self.runs.len() * 4 + self.dist.len()
    }

    /// Row `r`'s lit runs (none outside the image).
    fn row(&self, r: usize) -> &[(u16, u16)] {
        match r.checked_sub(self.row0 as usize) {
            Some(k) if k + 1 < self.row_start.len() => {
                &self.runs[self.row_start[k] as usize..self.row_start[k + 1] as usize]
            }
            _ => &[],
        }
    }

    /// Chessboard distance (coarse cells, saturating at 255) from cell (cx, cy) to the nearest
    /// cell holding a lit pixel, or less where that cell lies outside the stored window.
    fn cell_distance(&self, cx: u32, cy: u32) -> u8 {
        let Some([x0, x1, y0, y1]) = self.lit_cells else {
            return 255;
        };
        let [wx, wy, ww, wh] = self.window;
        if (wx..wx + ww).contains(&cx) && (wy..wy + wh).contains(&cy) {
            return self.dist[((cy - wy) * ww + cx - wx) as usize];
        }
        // The distance to the lit cells' box: none lies nearer.
        let gap = |c: u32, lo: u32, hi: u32| lo.saturating_sub(c).max(c.saturating_sub(hi));
        gap(cx, x0, x1).max(gap(cy, y0, y1)).min(255) as u8
    }

    /// Whether every pixel that the square of half-size `r` (px) about (u, v) (pixel coordinates,
    /// top-left corner 0) overlaps is dark. A camera integrates over its pixels: light in the part of
    /// a pixel that the square covers makes that pixel lit, however far its centre lies outside the
    /// square, so a square is known dark only when every pixel it touches is (judged by centres, a
    /// rim cell was called dark through the dark centre of a pixel whose other half held the rim:
    /// the disc lost 1.3–2.7 mm of radius). `None` when the square is not wholly inside the image
    /// (the camera does not see all of it, so it says nothing).
    pub fn dark(&self, u: f64, v: f64, r: f64) -> Option<bool> {
        let (x0, x1, y0, y1) = (u - r, u + r, v - r, v + r);
        if !(x0 >= 0.0 && y0 >= 0.0 && x1 <= f64::from(self.width) && y1 <= f64::from(self.height)) {
            return None;
        }
        let last = |hi: f64, lo: f64, n: u32| ((hi.ceil() as i64 - 1).max(lo.floor() as i64)).min(i64::from(n) - 1);
        let (c0, c1) = (x0.floor() as i64, last(x1, x0, self.width));
        let (r0, r1) = (y0.floor() as i64, last(y1, y0, self.height));
        if r1 - r0 < EXACT_ROWS {
            return Some(self.rows_dark(c0, c1, r0, r1));
        }
        // Coarse: the cell of (u, v) and its chessboard distance d to light. Every lit pixel is then
        // more than (d − 1)·COARSE_PX px from (u, v) along x or y.
        let (cx, cy) = ((u / f64::from(COARSE_PX)) as u32, (v / f64::from(COARSE_PX)) as u32);
        let d = self.cell_distance(cx.min(self.cw - 1), cy.min(self.ch - 1));
        if f64::from(d.saturating_sub(1)) * f64::from(COARSE_PX) > r + 1.0 {
            return Some(true);
        }
        Some(false)
    }

    /// Whether every pixel whose centre lies in the square of half-size `r` (px) about (u, v) is lit;
    /// `false` where that is not certain (the square is large, leaves the image or holds no pixel
    /// centre).
    pub fn lit(&self, u: f64, v: f64, r: f64) -> bool {
        let (x0, x1, y0, y1) = (u - r, u + r, v - r, v + r);
        if !(x0 >= 0.0 && y0 >= 0.0 && x1 <= f64::from(self.width) && y1 <= f64::from(self.height)) {
            return false;
        }
        let (c0, c1) = ((x0 - 0.5).floor() as i64, (x1 - 0.5).ceil() as i64);
        let (r0, r1) = ((y0 - 0.5).floor() as i64, (y1 - 0.5).ceil() as i64);
        if r1 - r0 + 1 > EXACT_ROWS || c0 < 0 || r0 < 0 || c1 >= i64::from(self.width) || r1 >= i64::from(self.height) {
            return false;
        }
        // The pixels around the square too (a surface between pixel centres is lit only if both are).
        (r0..=r1).all(|r| {
            let runs = self.row(r as usize);
            let i = runs.partition_point(|&(_, e)| i64::from(e) <= c0);
            runs.get(i)
                .is_some_and(|&(s, e)| i64::from(s) <= c0 && i64::from(e) > c1)
        })
    }

    /// Whether rows `r0..=r1` hold no lit pixel in columns `c0..=c1`.
    fn rows_dark(&self, c0: i64, c1: i64, r0: i64, r1: i64) -> bool {
        for r in r0.max(0)..=r1.min(i64::from(self.height) - 1) {
            let runs = self.row(r as usize);
            // First run ending after c0.
            let i = runs.partition_point(|&(_, e)| i64::from(e) <= c0);
            if let Some(&(s, _)) = runs.get(i) {
                if i64::from(s) <= c1 {
                    return false;
                }
            }
        }
        true
    }
}

/// The floor of [`LitMask::above_noise_with`]: `relative · max`, or [`NOISE_SIGMAS`] · `sigma` where
/// that is more.
fn noise_floor(max: f32, relative: f32, sigma: f32) -> f32 {
    (relative * max).max(NOISE_SIGMAS * sigma)
}

/// `img`'s largest finite value (cd/m²), 0 when none is positive.
fn largest(img: &LuminanceImage) -> f32 {
    img.data
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f32, f32::max)
}

/// Standard deviations of an image's noise ([`noise_sigma`]) a pixel reaches to be lit in
/// [`LitMask::above_noise`]: in a 1216 × 1021 image of Gaussian noise, 0.001 pixels on average lie
/// beyond 6 σ (0.36 beyond 5 σ).
pub const NOISE_SIGMAS: f32 = 6.0;

/// Fewest pixels [`noise_sigma`] estimates from.
pub const NOISE_MIN_PIXELS: usize = 64;

/// The median of |x| for x drawn from a zero-mean normal distribution, in standard deviations.
const HALF_NORMAL_MEDIAN: f32 = 0.674_49;

/// One standard deviation (cd/m²) of the noise in `img`'s dark pixels, from what only noise makes
/// in a dark-corrected luminance image:
/// - **negative pixels**: when at least [`NOISE_MIN_PIXELS`] are negative, their median magnitude
///   over the median of a half-normal distribution;
/// - else **noise clipped at zero**: when at least a fifth of the zero pixels (and
///   [`NOISE_MIN_PIXELS`]) have a positive right-hand neighbour, those neighbours' median over the
///   same (half the neighbours of a zero in clipped noise are positive; in a noise-free image the
///   zeros lie in runs and a zero's positive neighbour is an edge, a few per cent of them);
/// - else **0**: a noise-free image (the synthetic scans).
///
/// An image whose dark level is not corrected (noise about a positive offset) shows neither, and
/// is taken as noise-free.
pub fn noise_sigma(img: &LuminanceImage) -> f32 {
    let mut negative: Vec<f32> = img.data.iter().copied().filter(|v| *v < 0.0).map(|v| -v).collect();
    if negative.len() >= NOISE_MIN_PIXELS {
        return median(&mut negative) / HALF_NORMAL_MEDIAN;
    }
    let w = img.width as usize;
    let mut zeros = 0usize;
    let mut beside: Vec<f32> = Vec::new();
    for row in img.data.chunks_exact(w.max(1)) {
        for pair in row.windows(2) {
            if pair[0] == 0.0 {
                zeros += 1;
                if pair[1] > 0.0 && pair[1].is_finite() {
                    beside.push(pair[1]);
                }
            }
        }
    }
    if beside.len() >= NOISE_MIN_PIXELS && 5 * beside.len() >= zeros {
        return median(&mut beside) / HALF_NORMAL_MEDIAN;
    }
    0.0
}

/// The median of `v` (not empty; reordered).
fn median(v: &mut [f32]) -> f32 {
    let k = v.len() / 2;
    *v.select_nth_unstable_by(k, f32::total_cmp).1
}

/// Chessboard distance (saturating at 255) from each cell to the nearest `true` cell; all 255 when
/// there is none. Two passes with the 8-neighbourhood (exact for the chessboard metric).
fn chessboard(lit: &[bool], w: usize, h: usize) -> Vec<u8> {
    let mut d: Vec<u8> = lit.iter().map(|&l| if l { 0 } else { 255 }).collect();
    let at = |x: usize, y: usize| y * w + x;
    for y in 0..h {
        for x in 0..w {
            let mut m = d[at(x, y)];
            if x > 0 {
                m = m.min(d[at(x - 1, y)].saturating_add(1));
            }
            if y > 0 {
                m = m.min(d[at(x, y - 1)].saturating_add(1));
                if x > 0 {
                    m = m.min(d[at(x - 1, y - 1)].saturating_add(1));
                }
                if x + 1 < w {
                    m = m.min(d[at(x + 1, y - 1)].saturating_add(1));
                }
            }
            d[at(x, y)] = m;
        }
    }
    for y in (0..h).rev() {
        for x in (0..w).rev() {
            let mut m = d[at(x, y)];
            if x + 1 < w {
                m = m.min(d[at(x + 1, y)].saturating_add(1));
            }
            if y + 1 < h {
                m = m.min(d[at(x, y + 1)].saturating_add(1));
                if x + 1 < w {
                    m = m.min(d[at(x + 1, y + 1)].saturating_add(1));
                }
                if x > 0 {
                    m = m.min(d[at(x - 1, y + 1)].saturating_add(1));
                }
            }
            d[at(x, y)] = m;
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image_with(w: u32, h: u32, lit: &[(u32, u32)]) -> LuminanceImage {
        let mut img = LuminanceImage::zeros(w, h);
        for &(c, r) in lit {
            img.data[(r * w + c) as usize] = 100.0;
        }
        img
    }

    /// Whether the square of half-size `r` about (u, v) overlaps none of the `lit` pixels (column,
    /// row), by brute force.
    fn truly_dark(lit: &[(u32, u32)], u: f64, v: f64, r: f64) -> bool {
        !lit.iter().any(|&(c, rr)| {
            let (x, y) = (f64::from(c), f64::from(rr));
            x < u + r && x + 1.0 > u - r && y < v + r && y + 1.0 > v - r
        })
    }

    #[test]
    fn a_small_source_in_a_full_size_image_keeps_a_small_mask() {
        // A 40 × 30 px source in a full-size capture: the mask holds its rows and the distance map
        // around it only (it held 4 KB of row starts and 19 KB of distances for any image).
        let mut lit = Vec::new();
        for r in 500..530u32 {
            for c in 600..640u32 {
                if (c + r) % 7 != 0 {
                    lit.push((c, r));
                }
            }
        }
        let img = image_with(1216, 1021, &lit);
        let m = LitMask::of(&img, 1e-3).unwrap();
        assert_eq!(m.lit_pixels, lit.len() as u64);
        assert!(m.bytes() < 4096, "{} bytes", m.bytes());
        assert_eq!(m.lit_box(), Some([600.0, 640.0, 500.0, 530.0]));
        assert_eq!(m.lit_centres(usize::MAX).len(), lit.len());
        // Squares all over the image, brute-forced: never dark where a lit pixel is; exact where
        // the runs answer; dark far from the source, inside and outside the stored window.
        let mut rng = 12345u64;
        let mut next = |n: f64| {
            rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (rng >> 11) as f64 / (1u64 << 53) as f64 * n
        };
        for i in 0..3000 {
            let r = if i % 2 == 0 { next(10.0) } else { next(200.0) };
            let (u, v) = (r + next(1216.0 - 2.0 * r), r + next(1021.0 - 2.0 * r));
            let truth = truly_dark(&lit, u, v, r);
            let got = m.dark(u, v, r).unwrap();
            assert!(!got || truth, "({u}, {v}, {r}) called dark but holds a lit pixel");
            if 2.0 * r <= EXACT_ROWS as f64 - 2.0 {
                assert_eq!(got, truth, "({u}, {v}, {r})");
            }
        }
        assert_eq!(m.dark(700.0, 515.0, 30.0), Some(true), "beside it, in the window");
        assert_eq!(
            m.dark(100.0, 100.0, 60.0),
            Some(true),
            "far from it, outside the window"
        );
        assert_eq!(m.dark(620.0, 515.0, 40.0), Some(false));
        assert!(m.lit(612.5, 512.5, 0.4));
        assert!(!m.lit(100.5, 100.5, 0.4));
    }

    #[test]
    fn dark_squares_are_exactly_those_overlapping_no_lit_pixel() {
        let img = image_with(200, 150, &[(50, 40), (51, 40), (120, 100)]);
        let m = LitMask::of(&img, 1e-3).unwrap();
        assert_eq!(m.lit_pixels, 3);
        // Brute force over many squares, small (exact path) and large (coarse path: may say "not
        // dark" where it is, never "dark" where it is not).
        let mut exact_agree = 0;
        for (i, &(u, v, r)) in [
            (50.5, 40.5, 0.4),
            (53.0, 40.5, 1.4),
            (53.0, 40.5, 1.6),
            (10.0, 10.0, 5.0),
            (60.0, 60.0, 30.0),
            (100.0, 75.0, 60.0),
            (120.5, 100.5, 0.1),
            (118.0, 98.0, 2.0),
            (150.0, 60.0, 40.0),
        ]
        .iter()
        .enumerate()
        {
            let truth = truly_dark(&[(50, 40), (51, 40), (120, 100)], u, v, r);
            let got = m.dark(u, v, r).unwrap();
            assert!(!got || truth, "square {i} called dark but holds a lit pixel");
            if 2.0 * r <= EXACT_ROWS as f64 - 2.0 {
                assert_eq!(got, truth, "square {i}");
                exact_agree += 1;
            }
        }
        assert!(exact_agree >= 5);
        // Far from light, the coarse map says dark.
        assert_eq!(m.dark(160.0, 30.0, 20.0), Some(true));
        // Outside the frame: no answer.
        assert_eq!(m.dark(5.0, 5.0, 6.0), None);
        // A square smaller than a pixel between pixel centres: the pixels it overlaps decide.
        let mut one = LuminanceImage::zeros(16, 16);
        one.data[5 * 16 + 5] = 1.0;
        let m1 = LitMask::of(&one, 1e-3).unwrap();
        assert_eq!(
            m1.dark(5.9, 5.9, 0.05),
            Some(false),
            "inside the lit pixel, no centre in the square"
        );
        assert_eq!(
            m1.dark(6.0, 6.0, 0.05),
            Some(false),
            "on the corner it shares with the lit pixel"
        );
        assert_eq!(m1.dark(6.2, 6.2, 0.05), Some(true), "inside the dark pixel beside it");
        let none = LitMask::of(&LuminanceImage::zeros(16, 16), 1e-3).unwrap();
        assert_eq!((none.lit_pixels, none.lit_box()), (0, None));
        assert_eq!(none.dark(8.0, 8.0, 7.0), Some(true));
        assert!(!none.lit(8.0, 8.0, 1.0));
        // Lit: only where every pixel around the square is.
        let mut block = LuminanceImage::zeros(40, 40);
        for r in 10..20 {
            for c in 10..20 {
                block.data[r * 40 + c] = 1.0;
            }
        }
        let b = LitMask::of(&block, 1e-3).unwrap();
        assert!(b.lit(15.0, 15.0, 3.0));
        assert!(!b.lit(11.0, 15.0, 1.0));
        assert!(!b.lit(25.0, 15.0, 1.0));
        assert!(!b.lit(15.0, 15.0, 20.0));
    }

    /// Standard normal numbers from a fixed seed (splitmix64 and Box–Muller).
    fn normals(n: usize, seed: u64) -> Vec<f32> {
        let mut state = seed;
        let mut next = || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let (u, v) = (next().max(1e-300), next());
                ((-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()) as f32
            })
            .collect()
    }

    /// A 200 × 150 image: 10⁶ cd/m² in a 4 × 4 spot, 1 cd/m² in the box [40, 160) × [30, 120),
    /// 0 elsewhere; plus Gaussian noise of `sigma` cd/m² (clipped at zero when `clip`).
    fn spot_on_background(sigma: f32, clip: bool) -> LuminanceImage {
        let (w, h) = (200u32, 150u32);
        let mut img = LuminanceImage::zeros(w, h);
        let noise = normals((w * h) as usize, 7);
        for r in 0..h {
            for c in 0..w {
                let i = (r * w + c) as usize;
                let mut v = if (98..102).contains(&c) && (73..77).contains(&r) {
                    1.0e6
                } else if (40..160).contains(&c) && (30..120).contains(&r) {
                    1.0
                } else {
                    0.0
                };
                v += sigma * noise[i];
                img.data[i] = if clip { v.max(0.0) } else { v };
            }
        }
        img
    }

    #[test]
    fn noise_is_measured_from_negative_pixels_or_zeros_beside_clipped_noise() {
        assert_eq!(noise_sigma(&spot_on_background(0.0, false)), 0.0, "noise-free");
        for clip in [false, true] {
            let s = noise_sigma(&spot_on_background(0.05, clip));
            assert!((s / 0.05 - 1.0).abs() < 0.1, "clip {clip}: {s} for 0.05");
        }
        // A noise-free image of thin stripes: zeros beside lit pixels are edges, not noise.
        let stripes: Vec<(u32, u32)> = (0..64).flat_map(|r| (0..64).step_by(8).map(move |c| (c, r))).collect();
        assert_eq!(noise_sigma(&image_with(64, 64, &stripes)), 0.0);
    }

    #[test]
    fn masks_above_the_noise_find_a_dim_background_beside_a_bright_spot() {
        let background = 120 * 90;
        // Relative to the spot, the background is below the default threshold: only the spot.
        let m = LitMask::of(&spot_on_background(0.0, false), 1e-4).unwrap();
        assert_eq!(m.lit_pixels, 16);
        // Deeper, noise-free: the whole background.
        let m = LitMask::above_noise(&spot_on_background(0.0, false), 1e-7).unwrap();
        assert_eq!(m.lit_pixels, background);
        // With noise of 0.05 cd/m², clipped or not: the background, and no pixel of the noise
        // around it (6 σ = 0.3 cd/m²; 17,400 noise pixels).
        for clip in [false, true] {
            let m = LitMask::above_noise(&spot_on_background(0.05, clip), 1e-7).unwrap();
            assert_eq!(m.lit_pixels, background, "clip {clip}");
            assert!((0.29..0.33).contains(&m.floor_cd_m2), "clip {clip}: {}", m.floor_cd_m2);
        }
        // Noise as bright as the background hides it: a mask made at 1e-7 of the spot alone would
        // light half the image.
        let m = LitMask::above_noise(&spot_on_background(1.0, false), 1e-7).unwrap();
        assert!(m.lit_pixels < 100, "{}", m.lit_pixels);
    }

    #[test]
    fn counting_above_the_noise_counts_what_the_mask_lights() {
        for (sigma, clip) in [(0.0, false), (0.05, false), (0.05, true), (1.0, false)] {
            let img = spot_on_background(sigma, clip);
            for relative in [1e-7, 1e-4, 0.5] {
                let m = LitMask::above_noise(&img, relative).unwrap();
                let n = LitMask::count_above_noise_with(&img, relative, noise_sigma(&img)).unwrap();
                assert_eq!(n, m.lit_pixels, "sigma {sigma} clip {clip} relative {relative}");
            }
        }
        let dark = LuminanceImage {
            width: 4,
            height: 2,
            data: vec![0.0; 8],
        };
        assert_eq!(LitMask::count_above_noise_with(&dark, 1e-7, 0.0), Some(0));
    }

    #[test]
    fn chessboard_distances() {
        let mut lit = vec![false; 25];
        lit[12] = true;
        let d = chessboard(&lit, 5, 5);
        assert_eq!(d[12], 0);
        assert_eq!(d[0], 2);
        assert_eq!(d[7], 1);
        assert_eq!(chessboard(&[false; 4], 2, 2), vec![255; 4]);
    }
}

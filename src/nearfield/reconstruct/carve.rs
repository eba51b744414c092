//! Space carving on an octree: a cube of space holds no luminous surface when some camera that sees
//! all of it sees only darkness there, unless (at the finest level) the dark cameras may be seeing
//! the back of a one-sided emitter the lit ones see the front of. Cubes start at 8 per axis over
//! the content box and are split until the finest level; a cube every camera sees wholly lit is
//! kept with all its descendants without further tests, so work grows with the surface, not the
//! volume.

use glam::DVec3;
use rayon::prelude::*;

use super::hemisphere::{in_open_hemisphere, separable};
use super::mask::LitMask;
use crate::nearfield::rayset::{Camera, Intrinsics};

/// One capture camera with its lit mask.
#[derive(Debug)]
pub struct View {
    /// Pose (luminaire frame, m).
    pub camera: Camera,
    /// Intrinsics.
    pub intrinsics: Intrinsics,
    /// Where its image holds light.
    pub mask: LitMask,
}

/// What a view says about a cube.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Verdict {
    /// Every pixel of its footprint is dark: nothing luminous inside.
    Dark,
    /// Every pixel of its footprint is lit.
    Lit,
    /// Some pixel of its footprint may be lit (or the footprint is too large to tell).
    Mixed,
    /// Not wholly in view (or behind the camera): no evidence.
    Unseen,
}

impl View {
    fn judge(&self, centre: DVec3, half_m: f64) -> Verdict {
        let d = centre - self.camera.position_m;
        let c = self.camera.to_camera(d);
        let rho = half_m * 3f64.sqrt();
        if c.z - rho <= 1e-9 {
            return Verdict::Unseen;
        }
        let Some(px) = self.intrinsics.project(c) else {
            return Verdict::Unseen;
        };
        let t2 = (c.x * c.x + c.y * c.y) / (c.z * c.z);
        let f = self.intrinsics.focal_px.x.max(self.intrinsics.focal_px.y);
        // The bounding sphere's image lies within this square (off-axis stretch included).
        let r = rho * f * (1.0 + t2) / (c.z - rho);
        match self.mask.dark(px.x, px.y, r) {
            Some(true) => Verdict::Dark,
            Some(false) if self.mask.lit(px.x, px.y, r) => Verdict::Lit,
            Some(false) => Verdict::Mixed,
            None => Verdict::Unseen,
        }
    }
}

/// Flags, one bit each (a 256³ grid takes 2 MiB).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cells {
    bits: Vec<u64>,
    len: usize,
}

impl Cells {
    /// `len` flags, all false.
    pub fn new(len: usize) -> Self {
        Cells {
            bits: vec![0; len.div_ceil(64)],
            len,
        }
    }

    /// Number of flags.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Flag `i` (false past the end).
    pub fn get(&self, i: usize) -> bool {
        i < self.len && self.bits[i / 64] >> (i % 64) & 1 == 1
    }

    /// Sets flag `i` (ignored past the end).
    pub fn set(&mut self, i: usize, on: bool) {
        if i < self.len {
            let (w, b) = (i / 64, 1u64 << (i % 64));
            if on {
                self.bits[w] |= b;
            } else {
                self.bits[w] &= !b;
            }
        }
    }

    /// Sets every flag of `range` (clipped to the flags).
    pub fn fill(&mut self, range: std::ops::Range<usize>) {
        for i in range.start..range.end.min(self.len) {
            self.bits[i / 64] |= 1u64 << (i % 64);
        }
    }

    /// Flags set.
    pub fn count(&self) -> usize {
        self.bits.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// Every flag in order.
    pub fn iter(&self) -> impl Iterator<Item = bool> + '_ {
        (0..self.len).map(|i| self.get(i))
    }
}

/// The carved volume: cubes of `voxel_m` over `n`³ cells from `origin`, occupied or not.
#[derive(Debug, Clone)]
pub struct Occupancy {
    /// Corner of cell (0, 0, 0) (m, luminaire frame).
    pub origin: DVec3,
    /// Cell edge (m).
    pub voxel_m: f64,
    /// Cells per axis.
    pub n: usize,
    /// `n³` flags, x fastest.
    pub cells: Cells,
    /// Cube tests made (one cube against one view), for the report.
    pub tests: u64,
}

impl Occupancy {
    /// The grid of `self` with other flags (`cells.len()` must be n³).
    pub fn with_cells(&self, cells: Cells) -> Occupancy {
        Occupancy {
            origin: self.origin,
            voxel_m: self.voxel_m,
            n: self.n,
            cells,
            tests: self.tests,
        }
    }

    /// Whether cell (x, y, z) is occupied (false outside the grid).
    pub fn at(&self, x: i64, y: i64, z: i64) -> bool {
        let n = self.n as i64;
        (0..n).contains(&x)
            && (0..n).contains(&y)
            && (0..n).contains(&z)
            && self.cells.get(((z * n + y) * n + x) as usize)
    }

    /// Occupied cells.
    pub fn count(&self) -> usize {
        self.cells.count()
    }

    /// Centre of cell (x, y, z) (m).
    pub fn centre(&self, x: usize, y: usize, z: usize) -> DVec3 {
        self.origin + (DVec3::new(x as f64, y as f64, z as f64) + 0.5) * self.voxel_m
    }
}

/// A coarse cube: `Some(false)` (carve: some camera sees it all dark, none sees light in it),
/// `Some(true)` (keep with every descendant: every camera sees it wholly lit) or `None` (split).
/// Stops at the first camera that rules out both. Returns the tests made.
fn screen(views: &[View], c: DVec3, h: f64) -> (Option<bool>, u64) {
    let (mut dark, mut light, mut all_lit) = (false, false, !views.is_empty());
    for (k, v) in views.iter().enumerate() {
        match v.judge(c, h) {
            Verdict::Dark => {
                dark = true;
                all_lit = false;
            }
            Verdict::Lit => light = true,
            Verdict::Mixed => {
                light = true;
                all_lit = false;
            }
            Verdict::Unseen => all_lit = false,
        }
        if light && !all_lit {
            return (None, k as u64 + 1);
        }
    }
    let n = views.len() as u64;
    if all_lit {
        (Some(true), n)
    } else if dark && !light {
        (Some(false), n)
    } else {
        (None, n)
    }
}

/// A finest cube: kept when no camera sees it all dark, or when the cameras that see it wholly lit
/// (or, where none does, those that see light in part of it) and those that see it dark fit `rule`.
/// [`Rule::OneSided`]: some plane through it has every camera that sees it wholly lit in front and
/// every camera that sees it dark behind ([`in_open_hemisphere`]), or in front by less than
/// `grazing` (sine of the elevation): it may hold a one-sided emitter whose back those dark cameras
/// see (a surface seen more obliquely than that may cover less than a sample, and a camera that
/// samples points, not areas, can miss it).
///
/// `views` should be ordered so that every prefix is spread over the sphere: the test stops at the
/// first checkpoint (32, 64, 128, … views) where the evidence already rules the cube out.
fn decide(views: &[View], c: DVec3, h: f64, rule: Rule) -> (Option<bool>, u64) {
    let mut lit: Vec<DVec3> = Vec::new();
    let mut mixed: Vec<DVec3> = Vec::new();
    let mut dark: Vec<DVec3> = Vec::new();
    let mut checkpoint = 32usize;
    // Where no camera sees the cube wholly lit (within a footprint of a silhouette: a rim), the
    // cameras that see light in part of it stand in for the lit ones; without them a source's rim
    // would be carved back by a footprint (the disc's by 1.3–2.7 mm), and a surface proxy shows
    // light only where it is.
    let fits = |lit: &[DVec3], mixed: &[DVec3], dark: &[DVec3]| {
        dark.is_empty() || rule.fits(if lit.is_empty() { mixed } else { lit }, dark)
    };
    for (k, v) in views.iter().enumerate() {
        let towards = (v.camera.position_m - c).normalize_or_zero();
        match v.judge(c, h) {
            Verdict::Dark => dark.push(towards),
            Verdict::Lit => lit.push(towards),
            // A footprint only partly lit proves little: beside a silhouette, a grazing camera sees
            // the light behind the cube along its whole line of sight.
            Verdict::Mixed => mixed.push(towards),
            Verdict::Unseen => {}
        }
        if k + 1 == checkpoint && k + 1 < views.len() {
            checkpoint *= 2;
            if !fits(&lit, &mixed, &dark) {
                return (Some(false), k as u64 + 1);
            }
        }
    }
    (Some(fits(&lit, &mixed, &dark)), views.len() as u64)
}

/// Which mix of cameras that see a finest cube lit and dark still lets it hold an emitter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rule {
    /// An emitter facing a half-space (the lit and the reversed dark directions
    /// [`in_open_hemisphere`]): the dark cameras see its back, or its front at an elevation below
    /// `grazing` (sine).
    OneSided {
        /// Sine of the grazing tolerance.
        grazing: f64,
    },
    /// A directional emitter: the lit cameras lie in a cap (a cone of any width) that holds no
    /// dark one ([`separable`]). It also keeps the space in front of and behind a flat source,
    /// symmetrically (a cell there sees the source over a cap of directions), which
    /// [`super::mesh::collapse_thin`] then collapses onto the source: the fallback for beams and
    /// small features that the one-sided rule carves away.
    Directional,
}

impl Rule {
    fn fits(self, lit: &[DVec3], dark: &[DVec3]) -> bool {
        match self {
            Rule::OneSided { grazing } => one_sided(lit, dark, grazing),
            Rule::Directional => !lit.is_empty() && separable(lit, dark),
        }
    }
}

/// Whether the cameras that see a cube lit (`lit`, directions towards them) and those that see it
/// dark (`dark`) fit one emitter facing a half-space: some plane through the cube has every lit
/// camera in front and every dark one behind it or in front by less than `grazing` (sine of the
/// elevation; seen that obliquely, a surface may cover less than a sample).
///
/// The plane is free: for a unit normal `n` near the mean lit direction `m`, `n·d < grazing` is
/// `n·(grazing·m − d) > 0` up to the factor `n·m` ≈ 1, so the test is one open-hemisphere test on
/// the lit directions and the shifted, reversed dark ones. The rule it replaced did not count the
/// dark cameras within `grazing` of the plane across `m` itself; at a flat source's corner the lit
/// cameras' spread is lopsided, `m` tilts by 3–6°, and cameras 0.6° below the surface (which see
/// the corner as the tapering end of a sliver, thinner there than a sample) carved it: two-planes'
/// back plane lost a 20 × 25 mm corner.
fn one_sided(lit: &[DVec3], dark: &[DVec3], grazing: f64) -> bool {
    if lit.is_empty() {
        return false;
    }
    let mean = lit.iter().copied().sum::<DVec3>().normalize_or_zero();
    let mut dirs: Vec<DVec3> = lit.to_vec();
    dirs.extend(dark.iter().map(|d| grazing * mean - *d));
    in_open_hemisphere(&dirs)
}

/// `0..n` in an order whose every prefix is spread over the index range (a multiplicative stride
/// coprime with `n`), so that a view order sorted by direction becomes spread.
pub fn spread_order(n: usize) -> Vec<usize> {
    if n < 3 {
        return (0..n).collect();
    }
    // Near n / golden ratio, coprime with n.
    let mut stride = ((n as f64) * 0.618_033_988_75).round() as usize;
    while gcd(stride, n) != 1 {
        stride += 1;
    }
    (0..n).map(|i| i * stride % n).collect()
}

fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// Cells per axis at the coarsest level.
pub const BASE_CELLS: usize = 8;

/// Split cells whose children are made and judged together (8 children each).
const PARENTS_PER_CHUNK: usize = 1 << 14;

/// A cell's (x, y, z) at its level (each below 1024) in one word.
fn pack([x, y, z]: [u32; 3]) -> u32 {
    x | (y << 10) | (z << 20)
}

/// [`pack`]'s inverse.
fn unpack(p: u32) -> [u32; 3] {
    [p & 1023, (p >> 10) & 1023, p >> 20]
}

/// Carves the cube of half-size `half_m` about `centre` down to `BASE_CELLS · 2^levels` cells per
/// axis; cubes wholly outside the ball of `content_m` about `centre` are empty. `progress(level,
/// levels)` after each level.
pub fn carve(
    views: &[View],
    centre: DVec3,
    half_m: f64,
    content_m: f64,
    levels: u32,
    rule: Rule,
    progress: &(dyn Fn(u32, u32) + Sync),
) -> Occupancy {
    let n = BASE_CELLS << levels;
    let origin = centre - DVec3::splat(half_m);
    let mut cells = Cells::new(n * n * n);
    let mut tests = 0u64;
    // Cells (packed by `pack`) of the level before that were split: their children are judged now.
    // Children are made a chunk of parents at a time, so memory holds the undecided cells of one
    // level (the finest level's children, 9 million for a 200 mm disc at 1.1 mm cells, are never
    // all held). Level 0's cells are the children of a coarser level of BASE_CELLS / 2 per axis.
    // The split cells are held in lists of at most PARENTS_PER_CHUNK (a single list grown by doubling
    // held up to three times its length while it grew), each freed once its children are made.
    let half = (BASE_CELLS / 2) as u32;
    let mut parents: Vec<Vec<u32>> = vec![(0..half * half * half)
        .map(|i| pack([i % half, i / half % half, i / (half * half)]))
        .collect()];
    for level in 0..=levels {
        let size = 2.0 * half_m / (BASE_CELLS << level) as f64;
        let finest = level == levels;
        let scale = 1usize << (levels - level);
        // One list of parents (at most PARENTS_PER_CHUNK) at a time, freed once its children are made.
        let groups = parents.into_iter().map(|list| {
            list.iter()
                .flat_map(|&p| {
                    let [x, y, z] = unpack(p);
                    (0..8u32).map(move |k| pack([2 * x + (k & 1), 2 * y + ((k >> 1) & 1), 2 * z + (k >> 2)]))
                })
                .collect::<Vec<u32>>()
        });
        let mut next: Vec<Vec<u32>> = Vec::new();
        let mut split = Vec::new();
        for cells_now in groups {
            let judged: Vec<(u32, Option<bool>, u64)> = cells_now
                .par_iter()
                .map(|&p| {
                    let [x, y, z] = unpack(p);
                    let c = origin + (DVec3::new(f64::from(x), f64::from(y), f64::from(z)) + 0.5) * size;
                    let h = size / 2.0;
                    if (c - centre).length() - h * 3f64.sqrt() > content_m {
                        return (p, Some(false), 0);
                    }
                    let (verdict, k) = if finest {
                        decide(views, c, h, rule)
                    } else {
                        screen(views, c, h)
                    };
                    (p, verdict, k)
                })
                .collect();
            for (p, verdict, k) in judged {
                tests += k;
                match verdict {
                    Some(true) => {
                        let [x, y, z] = unpack(p);
                        let (x0, y0, z0) = (x as usize * scale, y as usize * scale, z as usize * scale);
                        for zz in z0..z0 + scale {
                            for yy in y0..y0 + scale {
                                let row = (zz * n + yy) * n;
                                cells.fill(row + x0..row + x0 + scale);
                            }
                        }
                    }
                    Some(false) => {}
                    None => {
                        split.push(p);
                        if split.len() == PARENTS_PER_CHUNK {
                            next.push(std::mem::take(&mut split));
                        }
                    }
                }
            }
        }
        if !split.is_empty() {
            next.push(split);
        }
        progress(level + 1, levels + 1);
        parents = next;
    }
    Occupancy {
        origin,
        voxel_m: 2.0 * half_m / n as f64,
        n,
        cells,
        tests,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_hold_one_bit_each_across_word_boundaries() {
        let mut c = Cells::new(130);
        assert_eq!((c.len(), c.count()), (130, 0));
        c.fill(60..70);
        c.set(129, true);
        c.set(200, true); // past the end: ignored
        assert_eq!(c.count(), 11);
        assert!(c.get(63) && c.get(64) && c.get(69) && c.get(129));
        assert!(!c.get(59) && !c.get(70) && !c.get(128) && !c.get(200));
        c.set(64, false);
        assert_eq!(c.count(), 10);
        assert!(!c.get(64) && c.get(65));
        let on: Vec<usize> = c.iter().enumerate().filter(|(_, b)| *b).map(|(i, _)| i).collect();
        assert_eq!(on, [60, 61, 62, 63, 65, 66, 67, 68, 69, 129]);
        c.fill(125..1000);
        assert_eq!(c.count(), 14); // 125…129, 129 already set
    }
}

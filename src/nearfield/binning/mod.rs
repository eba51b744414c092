//! Binning TM-25 rays into the luminance images of a virtual near-field goniophotometer.
//!
//! Cameras sit on a capture sphere (centre `c`, radius `r_s`) in a [`Layout`](super::layout::Layout); camera `i` at
//! direction `d_i` from the centre looks at the centre. A ray (start `p`, unit direction `k`, flux Φ)
//! leaving the luminaire towards direction `k` is what the camera whose direction is closest to `k`
//! would see:
//!
//! 1. **Camera**: the nearest camera by great-circle angle, `argmax_i k·d_i` (exact, through a bucket
//!    grid over the unit vectors; ties go to the lower index, so coincident pole cameras after the
//!    first get no rays). Each ray goes to exactly one camera, so flux is neither lost nor counted
//!    twice; rays with `k·d_i ≤ 0` for every camera (possible only for very sparse layouts) are
//!    dropped and reported.
//! 2. **Pixel**: where the ray's line crosses the camera's *object plane* (through `c`, perpendicular
//!    to `d_i`): `q = p + t·k`, `t = (c − p)·d_i / (k·d_i)`, projected with the pinhole of camera `i`.
//!    The object plane lies at distance `r_s` from the pinhole, so its pixel footprint is the same
//!    for every pixel, `A = (r_s/f_x)(r_s/f_y)`. Approximation: the ray is imaged as if it reached
//!    the pinhole along the camera's own line of sight through `q`; the angle between `k` and that
//!    line (at most about the Voronoi cell radius plus the source's angular size) is ignored.
//! 3. **Luminance**: `L = Φ_pixel / (A · Ω_i)`, where `Ω_i` is the solid angle of the directions
//!    assigned to camera `i`: its spherical Voronoi cell, computed exactly
//!    ([`NearestDirection::cell_solid_angle`]; sampled only for layouts so sparse that a cell reaches
//!    past ~85° from its camera). So
//!    `Σ_i Σ_pixels L·A·Ω_i = Σ Φ` of the rays that land inside an image: the binning conserves flux
//!    up to rays outside the field of view (reported) and f32 rounding.
//!
//! The images are noisy: a camera receives `rays × Ω_i / 4π` rays spread over its lit pixels; the
//! [`BinningReport`] says how many rays landed per lit pixel.
//!
//! - `nearest.rs`: [`NearestDirection`]: the nearest camera direction of a ray (a bucket grid over
//!   the unit vectors) and the solid angles of the spherical Voronoi cells;
//! - `bin.rs`: [`bin_rays`] with its [`BinningOptions`] and [`BinningReport`]: the binning pass.

mod bin;
mod nearest;

pub use bin::{bin_rays, BinnedScan, BinningOptions, BinningReport, MAX_TOTAL_PIXELS};
pub use nearest::NearestDirection;

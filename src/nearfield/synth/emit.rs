//! Forward tracing: the rays an analytic luminaire emits, as a ray-file measurement records them
//! (IES TM-25: start point, direction, luminous flux), for testing ray-file rendering against the
//! exact ray-caster.
//!
//! A ray is a line ℓ = (point, direction) with the luminance L(ℓ) the luminaire sends along it
//! ([`Luminaire::radiance`] seen from far along the line). Its flux density in line space is L:
//! Φ = ∫ L dA⊥ dω. Rays are drawn with density ∝ L, so each carries the same flux, as in measured
//! ray files:
//!
//! 1. **Where**: the proxy mesh's triangles ([`Luminaire::proxy`], the surfaces where the luminance
//!    appears) are cut into patches of at most 1/32768 of the total area. A point uniform on a
//!    patch and a cosine-weighted direction on either side of it are a uniform sample of the lines
//!    through that patch (density `1/(2π A)` in dA⊥ dω). A sample whose line meets another proxy
//!    surface first (nearer the observer) is dropped: that line belongs to the other surface.
//! 2. **Importance**: a pilot pass estimates each patch's largest luminance `M_j` (twice the largest
//!    of 24 samples, at least 10⁻³ of the patches' mean); patches are picked with probability
//!    ∝ `A_j M_j`, and a sample is kept with probability `min(1, L/M_j)`. The kept lines then have
//!    density ∝ L, i.e. equal flux, `2π Z / trials` with `Z = Σ A_j M_j`; a sample brighter than its
//!    patch's `M_j` is kept with the larger weight `L/M_j` times that, so the estimate stays unbiased.
//! 3. The ray starts at the surface point (the proxy hit), so ray origins lie on the emitting
//!    surfaces, as the start points of measured ray files lie on (or near) the source.
//!
//! The total flux of the rays is a Monte-Carlo estimate of [`Luminaire::flux_lm`] from every
//! sample drawn (its error falls as 1/√N), shared among the rays by their weights; deterministic
//! for a seed. Both cores are used.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::Luminaire;
use crate::nearfield::bvh::ProxyBvh;
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::proxy::triangles_of;
use crate::nearfield::tm25::{encode, CreationMethod, Tm25Flags, Tm25Header};

/// Most rays one call makes (5 · 10⁷: about 56 bytes per ray while tracing, 3 GB, and 28 bytes
/// per ray in a TM-25 file, 1.4 GB).
pub const MAX_RAYS: u64 = 50_000_000;

/// Patches per luminaire: the proxy's area is cut into pieces of at most 1/`PATCHES` of it.
const PATCHES: f64 = 32768.0;

/// Pilot samples per patch.
const PILOT: usize = 24;

/// Samples per parallel chunk of the main pass.
const CHUNK: usize = 1 << 15;

/// Rays leaving a luminaire (luminaire frame, metres).
#[derive(Debug, Clone, PartialEq)]
pub struct EmittedRays {
    /// Start points on the emitting surfaces (m).
    pub origins: Vec<DVec3>,
    /// Unit directions of travel (from the luminaire towards an observer).
    pub directions: Vec<DVec3>,
    /// Luminous flux of each ray (lm).
    pub flux_lm: Vec<f64>,
    /// Samples drawn in the main pass (kept or not).
    pub trials: u64,
}

impl EmittedRays {
    /// Number of rays.
    pub fn len(&self) -> usize {
        self.origins.len()
    }

    /// True when there are no rays.
    pub fn is_empty(&self) -> bool {
        self.origins.is_empty()
    }

    /// Σ flux of the rays (lm).
    pub fn total_flux_lm(&self) -> f64 {
        self.flux_lm.iter().sum()
    }

    /// The rays as an IES TM-25-13 file (simulated; columns x, y, z in mm, kx, ky, kz, luminous
    /// flux in lm; ray start position code 0), with `creator` as the ray file's creator.
    ///
    /// # Errors
    /// From [`encode`] (none for these columns).
    pub fn to_tm25(&self, creator: &str) -> Result<Vec<u8>> {
        let mut h = Tm25Header {
            creation_method: CreationMethod::Simulated,
            luminous_flux_lm: Some(self.total_flux_lm()),
            radiant_flux_w: None,
            ray_count: self.len() as u64,
            flags: Tm25Flags {
                luminous_flux: true,
                ..Tm25Flags::default()
            },
            ..Tm25Header::default()
        };
        h.description.ray_file_creator = creator.to_string();
        h.description.equipment = "lumiview synthetic goniophotometer (forward traced)".to_string();
        let mut rec = Vec::with_capacity(self.len() * 7);
        for ((p, k), f) in self.origins.iter().zip(&self.directions).zip(&self.flux_lm) {
            let mm = *p * 1000.0;
            rec.extend_from_slice(&[
                mm.x as f32,
                mm.y as f32,
                mm.z as f32,
                k.x as f32,
                k.y as f32,
                k.z as f32,
                *f as f32,
            ]);
        }
        encode(&h, &rec)
    }
}

/// A patch of the proxy: a triangle of the luminaire frame.
#[derive(Debug, Clone, Copy)]
struct Patch {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    area: f64,
    normal: DVec3,
}

impl Patch {
    fn new(a: DVec3, b: DVec3, c: DVec3) -> Self {
        let n = (b - a).cross(c - a);
        Self {
            a,
            b,
            c,
            area: 0.5 * n.length(),
            normal: n.normalize_or_zero(),
        }
    }

    fn split(&self) -> [Patch; 4] {
        let (ab, bc, ca) = (
            (self.a + self.b) / 2.0,
            (self.b + self.c) / 2.0,
            (self.c + self.a) / 2.0,
        );
        [
            Patch::new(self.a, ab, ca),
            Patch::new(ab, self.b, bc),
            Patch::new(ca, bc, self.c),
            Patch::new(ab, bc, ca),
        ]
    }

    /// A uniform point from two uniforms in [0, 1).
    fn point(&self, u: f64, v: f64) -> DVec3 {
        let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
        self.a + (self.b - self.a) * u + (self.c - self.a) * v
    }
}

/// SplitMix64: a small, fast, seedable generator (deterministic across platforms).
#[derive(Debug, Clone)]
struct Rng(u64);

impl Rng {
    /// A generator for one (seed, stream) pair. Both are hashed into the state: SplitMix64's
    /// states advance by a fixed odd constant, so states that differ by a multiple of it (as
    /// `seed ^ stream · constant` did for small seeds) walk the same sequence shifted, and whole
    /// chunks of rays came out as copies of each other.
    fn new(seed: u64, stream: u64) -> Self {
        Rng(mix(
            mix(seed).wrapping_add(0x632B_E59B_D9B4_E019) ^ mix(stream.wrapping_add(0xD1B5_4A32_D192_ED03))
        ))
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix(self.0)
    }

    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// SplitMix64's finaliser: a bijective 64-bit hash.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A cosine-weighted direction about `n`, on its front side or (half the time) its back side.
fn cosine_direction(n: DVec3, rng: &mut Rng) -> DVec3 {
    let side = if rng.uniform() < 0.5 { 1.0 } else { -1.0 };
    let (t, b) = n.any_orthonormal_pair();
    let (u, v) = (rng.uniform(), rng.uniform());
    let r = u.sqrt();
    let phi = std::f64::consts::TAU * v;
    let z = (1.0 - u).max(0.0).sqrt();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (side * z)).normalize()
}

/// Walker's alias table: O(1) draws from a discrete distribution.
#[derive(Debug, Clone)]
struct Alias {
    prob: Vec<f64>,
    alias: Vec<u32>,
}

impl Alias {
    fn new(weights: &[f64]) -> Self {
        let n = weights.len();
        let total: f64 = weights.iter().sum();
        let mut prob: Vec<f64> = weights.iter().map(|w| w * n as f64 / total).collect();
        let mut alias = vec![0u32; n];
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| prob[i] < 1.0);
        while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
            alias[s] = l as u32;
            prob[l] -= 1.0 - prob[s];
            if prob[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        for i in large.into_iter().chain(small) {
            prob[i] = 1.0;
        }
        Self { prob, alias }
    }

    fn draw(&self, rng: &mut Rng) -> usize {
        let i = ((rng.uniform() * self.prob.len() as f64) as usize).min(self.prob.len() - 1);
        if rng.uniform() < self.prob[i] {
            i
        } else {
            self.alias[i] as usize
        }
    }
}

/// Distance from a surface point along the line at which the observer is placed (beyond the
/// luminaire's bounds).
fn far_distance(lum: &dyn Luminaire) -> f64 {
    let b = lum.bounds();
    4.0 * (b.radius() + (b.centre()).length()).max(1e-3)
}

/// One sample through `patch`: the luminance along the line and whether the patch is its first
/// surface seen from the observer. Returns the point, the direction and L (0 when occluded).
fn sample(lum: &dyn Luminaire, bvh: &ProxyBvh, far: f64, patch: &Patch, rng: &mut Rng) -> (DVec3, DVec3, f64) {
    let p = patch.point(rng.uniform(), rng.uniform());
    let d = cosine_direction(patch.normal, rng);
    let eye = p + d * far;
    let eps = 1e-6 * far as f32;
    let v = |x: DVec3| Vec3::new(x.x as f32, x.y as f32, x.z as f32);
    if bvh.occluded(v(p + d * (4.0 * f64::from(eps))), v(eye), eps) {
        return (p, d, 0.0);
    }
    (p, d, lum.radiance(eye, -d).max(0.0))
}

/// Forward-traces `rays` rays of `lum` with `seed` (see the module docs). `progress` receives the
/// fraction done (0–1) now and then.
///
/// # Errors
/// [`NearfieldError::InvalidArgument`] for 0 or more than [`MAX_RAYS`] rays, or a luminaire whose
/// proxy has no area or that emits nothing through it.
pub fn emit_rays(lum: &dyn Luminaire, rays: u64, seed: u64, progress: &(dyn Fn(f64) + Sync)) -> Result<EmittedRays> {
    if rays == 0 || rays > MAX_RAYS {
        return Err(NearfieldError::invalid(
            "rays",
            format!("{rays}: expected 1…{MAX_RAYS}"),
        ));
    }
    let tris = triangles_of(&lum.proxy());
    let bvh = ProxyBvh::build(&tris)?;
    let mut patches: Vec<Patch> = tris
        .chunks_exact(3)
        .map(|t| {
            let d = |v: [f32; 3]| DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
            Patch::new(d(t[0]), d(t[1]), d(t[2]))
        })
        .filter(|p| p.area > 0.0)
        .collect();
    let total_area: f64 = patches.iter().map(|p| p.area).sum();
    if total_area.is_nan() || total_area <= 0.0 {
        return Err(NearfieldError::invalid(
            "luminaire",
            format!("{}: its proxy mesh has no area to emit from", lum.name()),
        ));
    }
    let target = total_area / PATCHES;
    let mut i = 0;
    while i < patches.len() {
        if patches[i].area > target && patches.len() < 4 * PATCHES as usize {
            let parts = patches[i].split();
            patches[i] = parts[0];
            patches.extend_from_slice(&parts[1..]);
        } else {
            i += 1;
        }
    }
    let far = far_distance(lum);
    // Pilot: the largest luminance per patch.
    let maxima: Vec<f64> = patches
        .par_iter()
        .enumerate()
        .map(|(j, patch)| {
            let mut rng = Rng::new(seed ^ 0x005E_ED0F_1107, j as u64);
            (0..PILOT)
                .map(|_| sample(lum, &bvh, far, patch, &mut rng).2)
                .fold(0.0, f64::max)
        })
        .collect();
    let mean_max = maxima.iter().zip(&patches).map(|(m, p)| m * p.area).sum::<f64>() / total_area;
    if mean_max.is_nan() || mean_max <= 0.0 {
        return Err(NearfieldError::invalid(
            "luminaire",
            format!("{}: no light leaves its proxy surfaces", lum.name()),
        ));
    }
    let bound: Vec<f64> = maxima.iter().map(|m| (2.0 * m).max(1e-3 * mean_max)).collect();
    let weights: Vec<f64> = bound.iter().zip(&patches).map(|(m, p)| m * p.area).collect();
    let z: f64 = weights.iter().sum();
    let alias = Alias::new(&weights);
    // Main pass, in deterministic chunks until enough rays are kept.
    // The last batch overshoots by at most one batch: reserve that too, so the vector never doubles.
    let batch = rayon::current_num_threads().max(1) * 4;
    let mut kept: Vec<(DVec3, DVec3, f64)> = Vec::with_capacity(rays as usize + batch * CHUNK);
    let mut trials: u64 = 0;
    let mut chunk_index: u64 = 0;
    while (kept.len() as u64) < rays {
        let results: Vec<Vec<(DVec3, DVec3, f64)>> = (0..batch as u64)
            .into_par_iter()
            .map(|c| {
                let mut rng = Rng::new(seed, chunk_index + c + 1);
                let mut out = Vec::new();
                for _ in 0..CHUNK {
                    let j = alias.draw(&mut rng);
                    let (p, d, l) = sample(lum, &bvh, far, &patches[j], &mut rng);
                    if l > 0.0 && rng.uniform() * bound[j] < l {
                        out.push((p, d, (l / bound[j]).max(1.0)));
                    }
                }
                out
            })
            .collect();
        chunk_index += batch as u64;
        for r in results {
            trials += CHUNK as u64;
            kept.extend(r);
            if kept.len() as u64 >= rays {
                break;
            }
        }
        progress((kept.len() as f64 / rays as f64).min(1.0));
        if trials > rays.saturating_mul(1_000_000) && kept.is_empty() {
            return Err(NearfieldError::invalid(
                "luminaire",
                format!("{}: no ray kept after {trials} samples", lum.name()),
            ));
        }
    }
    // The flux all kept samples estimate, shared by the first `rays` of them in proportion to
    // their weights (dropping the surplus of the last chunk must not drop its flux).
    let all_weight: f64 = kept.iter().map(|r| r.2).sum();
    let total_flux = std::f64::consts::TAU * z * all_weight / trials as f64;
    kept.truncate(rays as usize);
    let kept_weight: f64 = kept.iter().map(|r| r.2).sum();
    let unit = total_flux / kept_weight;
    Ok(EmittedRays {
        origins: kept.iter().map(|r| r.0).collect(),
        directions: kept.iter().map(|r| r.1).collect(),
        flux_lm: kept.iter().map(|r| r.2 * unit).collect(),
        trials,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nearfield::synth::luminaire;

    #[test]
    fn alias_table_draws_in_proportion() {
        let a = Alias::new(&[1.0, 3.0, 0.0, 4.0]);
        let mut rng = Rng::new(7, 0);
        let mut c = [0u32; 4];
        for _ in 0..80_000 {
            c[a.draw(&mut rng)] += 1;
        }
        assert_eq!(c[2], 0);
        for (k, want) in [(0, 0.125), (1, 0.375), (3, 0.5)] {
            let got = f64::from(c[k]) / 80_000.0;
            assert!((got - want).abs() < 0.01, "{k}: {got} vs {want}");
        }
    }

    #[test]
    fn every_ray_is_drawn_afresh() {
        // Rays from many chunks (streams) and two seeds: no ray repeats (streams of one
        // generator walking the same sequence shifted once made 5 of 6 rays copies).
        let lum = luminaire("disc").unwrap();
        let mut keys = Vec::new();
        for seed in [0, 1] {
            let r = emit_rays(lum.as_ref(), 200_000, seed, &|_| {}).unwrap();
            keys.extend(
                r.directions
                    .iter()
                    .map(|d| (d.x.to_bits(), d.y.to_bits(), d.z.to_bits())),
            );
        }
        let n = keys.len();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), n, "{} repeated rays of {n}", n - keys.len());
    }

    #[test]
    fn a_lambertian_disc_emits_its_flux_into_a_cosine_lobe() {
        let lum = luminaire("disc").unwrap();
        let r = emit_rays(lum.as_ref(), 40_000, 3, &|_| {}).unwrap();
        assert_eq!(r.len(), 40_000);
        let flux = lum.flux_lm();
        let rel = (r.total_flux_lm() - flux) / flux;
        assert!(rel.abs() < 0.03, "flux {} vs {flux}", r.total_flux_lm());
        // Equal flux per ray for a uniform emitter.
        let (lo, hi) = r
            .flux_lm
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), f| (a.min(*f), b.max(*f)));
        assert!((hi - lo) / hi < 1e-9, "{lo} … {hi}");
        // Downward (the disc faces −Z), cosine-distributed: mean |kz| = 2/3.
        assert!(r.directions.iter().all(|d| d.z < 0.0));
        let mean: f64 = r.directions.iter().map(|d| -d.z).sum::<f64>() / r.len() as f64;
        assert!((mean - 2.0 / 3.0).abs() < 0.01, "{mean}");
        // Origins on the disc.
        let b = lum.bounds();
        assert!(r.origins.iter().all(|p| b.contains(*p)));
    }

    #[test]
    fn deterministic_for_a_seed() {
        let lum = luminaire("rect").unwrap();
        let a = emit_rays(lum.as_ref(), 2_000, 9, &|_| {}).unwrap();
        let b = emit_rays(lum.as_ref(), 2_000, 9, &|_| {}).unwrap();
        assert_eq!(a, b);
    }
}

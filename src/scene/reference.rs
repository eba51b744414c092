//! The reference: a CPU path tracer for illuminance in diffuse scenes lit by photometric luminaires,
//! with the light split by bounce. For tests, evaluation and the C API's illuminance queries
//! (`lumi_scene_illuminance`), not for frames.
//!
//! # What it computes
//! The illuminance E (lx) at calculation points, each a position and the unit normal of the
//! surface (real or virtual, such as a work plane) that receives light from the hemisphere about
//! it: E = ∫ L_in(ω) cos θ dω. Surfaces are Lambertian with the scalar reflectance ρ_Y at the hit
//! ([`Scene::reflectance_y`]), two-sided; luminaires are [`SceneLuminaire`]s (point or area sources,
//! `scene::emitter`) and do not occlude. A calculation point does not occlude either.
//!
//! # The estimator
//! - Direct: E_d(x) = Σ_luminaires Σ_k I(s_k → x)/N · cos i_k / r_k² · V(x, s_k) (shadow rays;
//!   N = 1 for a point source, whose direct term is then exact; [`TraceOptions::area_samples`]
//!   stratified points on an opening otherwise), averaged over
//!   [`TraceOptions::direct_estimates`] independent estimates.
//! - Indirect, by path tracing with next-event estimation at every vertex: from x, a direction
//!   with density cos θ / π; at its closest hit y₁ (reflectance ρ₁, normal facing the ray) the
//!   radiance towards x is ρ₁ E(y₁)/π, so the estimator of the indirect part is
//!   ρ₁ (E_d(y₁) + ρ₂ (E_d(y₂) + …)): bounce k contributes β_k E_d(y_k), β_k = ρ₁⋯ρ_k over the
//!   roulette's survival probabilities. Each vertex's E_d uses one point per area luminaire.
//! - Russian roulette after [`TraceOptions::roulette_after`] bounces: the path continues with
//!   probability q = clamp(ρ_k, 0.05, 0.95) and β is divided by q, which keeps the estimate
//!   unbiased. [`TraceOptions::max_bounces`] is a safety cap only: what lies beyond it is at most
//!   ρ_max^max_bounces of the indirect light (10⁻⁶ for ρ = 0.8 and the default 64).
//! - Per point, the standard error of E is √(s_d²/D + s_i²/P) with s_d, s_i the sample standard
//!   deviations of the D direct estimates and the P paths' indirect sums.
//! - Deterministic: point i draws from `Pcg32::for_point(seed, i)`, so results do not depend on
//!   the number of threads (rayon, one task per point).

use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;

use super::bvh::{offset_m, Bvh};
use super::emitter::{Emitter, SceneLuminaire};
use super::error::{Result, SceneError};
use super::model::Scene;
use super::sampling::{cosine_hemisphere, Pcg32};

/// A calculation point: where illuminance is wanted and the normal of the receiving surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Position, scene metres.
    pub position_m: DVec3,
    /// Unit normal of the receiving side.
    pub normal: DVec3,
}

/// Most area samples per luminaire a [`TraceOptions`] may ask for.
pub const MAX_AREA_SAMPLES: usize = 1 << 20;

/// Most bounces a [`TraceOptions`] may ask for (a closed white room never ends a path by itself).
pub const MAX_BOUNCES: usize = 1024;

/// How much work the estimates get.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceOptions {
    /// Indirect paths per calculation point (0: direct light only).
    pub paths_per_point: usize,
    /// Independent estimates of the direct term per point (area luminaires; a scene of point
    /// sources needs 1).
    pub direct_estimates: usize,
    /// Points drawn on an area luminaire's opening per direct estimate (rounded up to a square).
    pub area_samples: usize,
    /// Bounces before Russian roulette starts.
    pub roulette_after: usize,
    /// Most bounces of a path (a safety cap; see the module's docs).
    pub max_bounces: usize,
    /// Seed of the random numbers.
    pub seed: u64,
}

impl Default for TraceOptions {
    fn default() -> Self {
        TraceOptions {
            paths_per_point: 256,
            direct_estimates: 4,
            area_samples: 64,
            roulette_after: 3,
            max_bounces: 64,
            seed: 1,
        }
    }
}

/// The illuminance at one point, split by bounce.
#[derive(Debug, Clone, PartialEq)]
pub struct PerBounce {
    /// Light straight from the luminaires, lx.
    pub direct_lx: f64,
    /// Light after 1, 2, … diffuse reflections, lx; as long as the deepest bounce any path of
    /// this point reached (empty without paths).
    pub bounces_lx: Vec<f64>,
    /// Direct plus every bounce, lx.
    pub total_lx: f64,
    /// Standard error of `direct_lx`, lx.
    pub direct_se_lx: f64,
    /// Standard error of `total_lx`, lx.
    pub total_se_lx: f64,
}

impl PerBounce {
    /// Everything but the direct light, lx.
    pub fn indirect_lx(&self) -> f64 {
        self.bounces_lx.iter().sum()
    }
}

/// A scene with its hierarchy and luminaires, ready for many queries. The hierarchy is shared
/// ([`Arc`]), so one built once serves tracers with different luminaires ([`Tracer::with_bvh`]).
#[derive(Debug, Clone)]
pub struct Tracer<'s> {
    scene: &'s Scene,
    bvh: Arc<Bvh>,
    emitters: Vec<Emitter>,
    offset_m: f64,
}

impl<'s> Tracer<'s> {
    /// Builds the hierarchy of `scene` and prepares the luminaires.
    ///
    /// Errors: a luminaire's matrix that is not a rotation and translation (argument
    /// `luminaires[i]`).
    pub fn new(scene: &'s Scene, luminaires: &[SceneLuminaire]) -> Result<Self> {
        let emitters = Emitter::prepare(luminaires)?;
        Ok(Tracer {
            scene,
            bvh: Arc::new(Bvh::build(scene)),
            emitters,
            offset_m: offset_m(&scene.bounds()),
        })
    }

    /// Prepares the luminaires over a hierarchy already built from `scene` with [`Bvh::build`]
    /// (kept and reused, e.g. by a scene loaded once and queried with different luminaires).
    ///
    /// Errors: a hierarchy over another number of triangles than `scene` has (argument `bvh`);
    /// those of [`Tracer::new`].
    pub fn with_bvh(scene: &'s Scene, bvh: Arc<Bvh>, luminaires: &[SceneLuminaire]) -> Result<Self> {
        if bvh.triangle_count() != scene.triangles().len() {
            return Err(SceneError::invalid(
                "bvh",
                format!(
                    "built over {} triangles, the scene has {}: build it from this scene",
                    bvh.triangle_count(),
                    scene.triangles().len()
                ),
            ));
        }
        Ok(Tracer {
            scene,
            bvh,
            emitters: Emitter::prepare(luminaires)?,
            offset_m: offset_m(&scene.bounds()),
        })
    }

    /// The hierarchy (for tests and other queries).
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// The illuminance at each point, in the order given.
    ///
    /// Errors: a point or normal that is not finite, or a zero normal (argument `points[i]`);
    /// `direct_estimates` or `area_samples` 0 (argument `options`).
    pub fn illuminance(&self, points: &[SurfacePoint], opts: &TraceOptions) -> Result<Vec<PerBounce>> {
        self.illuminance_with_progress(points, opts, &|_| ())
    }

    /// [`Tracer::illuminance`], calling `progress(done)` with the number of points finished as
    /// they finish (from the worker threads, in no particular order of points). The results are
    /// the same as without it.
    pub fn illuminance_with_progress(
        &self,
        points: &[SurfacePoint],
        opts: &TraceOptions,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Vec<PerBounce>> {
        if opts.direct_estimates == 0 || opts.area_samples == 0 {
            return Err(SceneError::invalid(
                "options",
                "direct_estimates and area_samples must be at least 1",
            ));
        }
        if opts.area_samples > MAX_AREA_SAMPLES || opts.max_bounces > MAX_BOUNCES {
            return Err(SceneError::invalid(
                "options",
                format!(
                    "area_samples {} (at most {MAX_AREA_SAMPLES}) or max_bounces {} (at most {MAX_BOUNCES}) too large",
                    opts.area_samples, opts.max_bounces
                ),
            ));
        }
        let mut unit = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            let n = p.normal.normalize_or_zero();
            if !p.position_m.is_finite() || n == DVec3::ZERO || !n.is_finite() {
                return Err(SceneError::invalid(
                    format!("points[{i}]"),
                    format!(
                        "position {} and normal {} must be finite, the normal non-zero",
                        p.position_m, p.normal
                    ),
                ));
            }
            unit.push(SurfacePoint {
                position_m: p.position_m,
                normal: n,
            });
        }
        let done = std::sync::atomic::AtomicUsize::new(0);
        Ok(unit
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let r = self.at_point(p, opts, &mut Pcg32::for_point(opts.seed, i as u64));
                progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                r
            })
            .collect())
    }

    /// The direct illuminance at `x` (unit normal `n`): one estimate over all luminaires.
    fn direct_lx(&self, x: DVec3, n: DVec3, area_samples: usize, rng: &mut Pcg32) -> f64 {
        self.emitters
            .iter()
            .map(|e| e.direct_lx(&self.bvh, x, n, area_samples, self.offset_m, rng))
            .sum()
    }

    fn at_point(&self, p: &SurfacePoint, opts: &TraceOptions, rng: &mut Pcg32) -> PerBounce {
        let (x, n) = (p.position_m, p.normal);
        let all_points = self.emitters.iter().all(Emitter::is_point);
        let estimates = if all_points { 1 } else { opts.direct_estimates };
        let mut direct = Stats::default();
        for _ in 0..estimates {
            direct.add(self.direct_lx(x, n, opts.area_samples, rng));
        }
        let mut bounces: Vec<f64> = Vec::new();
        let mut indirect = Stats::default();
        for _ in 0..opts.paths_per_point {
            indirect.add(self.path(x, n, opts, rng, &mut bounces));
        }
        let paths = opts.paths_per_point.max(1) as f64;
        for b in &mut bounces {
            *b /= paths;
        }
        let direct_lx = direct.mean();
        let total_lx = direct_lx + bounces.iter().sum::<f64>();
        let direct_se_lx = direct.std_error();
        let total_se_lx = (direct_se_lx.powi(2) + indirect.std_error().powi(2)).sqrt();
        PerBounce {
            direct_lx,
            bounces_lx: bounces,
            total_lx,
            direct_se_lx,
            total_se_lx,
        }
    }

    /// One path from `x` (normal `n`): adds each bounce's contribution to `bounces` and returns
    /// their sum.
    fn path(&self, x: DVec3, n: DVec3, opts: &TraceOptions, rng: &mut Pcg32, bounces: &mut Vec<f64>) -> f64 {
        let tris = self.scene.triangles();
        let mut origin = x + n * self.offset_m;
        let mut dir = cosine_hemisphere(n, rng.next_f64(), rng.next_f64());
        let mut beta = 1.0;
        let mut sum = 0.0;
        for bounce in 1..=opts.max_bounces {
            let Some(hit) = self.bvh.closest_hit(origin, dir, f64::INFINITY) else {
                break;
            };
            let t = tris[hit.triangle];
            let y = t[0] + hit.b1 * (t[1] - t[0]) + hit.b2 * (t[2] - t[0]);
            let mut ng = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
            if ng.dot(dir) > 0.0 {
                ng = -ng;
            }
            let rho = self.scene.reflectance_y(hit.triangle, hit.b1, hit.b2);
            beta *= rho;
            if beta.is_nan() || beta <= 0.0 {
                break;
            }
            let e = beta * self.direct_lx(y, ng, 1, rng);
            if bounces.len() < bounce {
                bounces.resize(bounce, 0.0);
            }
            bounces[bounce - 1] += e;
            sum += e;
            if bounce >= opts.roulette_after {
                let q = rho.clamp(0.05, 0.95);
                if rng.next_f64() >= q {
                    break;
                }
                beta /= q;
            }
            origin = y + ng * self.offset_m;
            dir = cosine_hemisphere(ng, rng.next_f64(), rng.next_f64());
        }
        sum
    }
}

/// The illuminance at `points` of `scene` lit by `luminaires` ([`Tracer::new`] then
/// [`Tracer::illuminance`]).
///
/// Errors: those of [`Tracer::new`] and [`Tracer::illuminance`].
pub fn illuminance(
    scene: &Scene,
    luminaires: &[SceneLuminaire],
    points: &[SurfacePoint],
    opts: &TraceOptions,
) -> Result<Vec<PerBounce>> {
    Tracer::new(scene, luminaires)?.illuminance(points, opts)
}

/// Running mean and variance (Welford).
#[derive(Debug, Default, Clone, Copy)]
struct Stats {
    n: usize,
    mean: f64,
    m2: f64,
}

impl Stats {
    fn add(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    fn mean(&self) -> f64 {
        self.mean
    }

    /// Standard error of the mean; 0 with fewer than two samples.
    fn std_error(&self) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        (self.m2 / (self.n - 1) as f64 / self.n as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_the_two_pass_formulas() {
        let xs = [1.0, 4.0, 4.0, 7.0, 9.5];
        let mut s = Stats::default();
        xs.iter().for_each(|&x| s.add(x));
        let mean = xs.iter().sum::<f64>() / 5.0;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 4.0;
        assert!((s.mean() - mean).abs() < 1e-12);
        assert!((s.std_error() - (var / 5.0).sqrt()).abs() < 1e-12);
        let mut one = Stats::default();
        one.add(3.0);
        assert_eq!(one.std_error(), 0.0);
    }
}

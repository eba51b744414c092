//! Inter-reflection by virtual point lights (instant radiosity): photons shot from the luminaires
//! in proportion to their intensity are traced through the scene; every diffuse reflection leaves
//! a virtual point light (VPL) that carries the flux it reflects. The GPU scene pass gathers them
//! per fragment; [`VplSet::illuminance_lx`] is the same gather on the CPU (tests and evaluation).
//!
//! # What it computes
//! - **Emission**: each luminaire's intensity I(ω) is tabulated at the centres of
//!   [`EMISSION_RINGS`] × [`EMISSION_SECTORS`] cells of 1° in γ and 1° in C (each with its exact solid
//!   angle ΔΩ, so a beam a few degrees wide spans several rings). The luminaires'
//!   flux estimates W_l = Σ_cells I_c ΔΩ form one distribution; photon k of N takes
//!   u_k = (k + ½)/N through it (systematic sampling: luminaires and cells get photons in
//!   proportion to their flux, stratified). Within its cell a photon's direction is uniform, its
//!   origin is a point of the luminous opening drawn as for direct light, and it carries
//!   (ΣW / N) · I(ω)/I_c lumen, so the expected total is the luminaires' flux.
//! - **Transport**: a photon's first hit with the scene (the CPU BVH; luminaires occlude nothing)
//!   reflects ρ_rgb of its flux: a VPL at the hit, normal facing the photon, flux Φ·ρ_rgb (the
//!   luminance-weighted Y of the RGB flux is lumen). The photon goes on from there in a
//!   cosine-distributed direction; from the second reflection on it survives with probability
//!   q = clamp(ρ_Y, 0.05, 0.95) and divides its flux by q (Russian roulette, unbiased), up to
//!   [`VplOptions::max_bounces`]. So the VPLs of generation k carry the k-th bounce, and all of
//!   them together carry every bounce: the "remaining bounces" are estimated by the same photons.
//! - **Gather**: a VPL at y (normal n_y, flux Φ) is a Lambertian emitter of intensity
//!   Φ cos θ_y / π, so at x (normal n_x) it gives E = Φ cos θ_y cos θ_x / (π · max(r², r_c²)).
//!   The clamp r_c ([`VplOptions::clamp_m`]) bounds each VPL's spike next to the surface it lies
//!   on (the estimator's bias: light within r_c of a VPL is under-counted). **No visibility**
//!   between VPL and receiver: light reaches places the VPL cannot see (under desks, behind
//!   cabinets), measured against the reference path tracer in docs/scene-lighting.md.
//! - Deterministic: the photons draw from `Pcg32` seeded with [`VplOptions::seed`] and the photon
//!   index.

use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;

use super::bvh::{offset_m, Bvh};
use super::emitter::{Emitter, SceneLuminaire};
use super::error::{Result, SceneError};
use super::model::{luminance_y, Scene};
use super::sampling::{cosine_hemisphere, Pcg32};
use crate::photometry::Photometry;

/// Emission table rings (equal steps in the angle from the luminaire's +Z axis).
pub const EMISSION_RINGS: usize = 180;
/// Emission table sectors per ring (equal steps in C).
pub const EMISSION_SECTORS: usize = 360;
/// Most photons one set may shoot.
pub const MAX_PHOTONS: usize = 1 << 20;

/// How the VPLs are made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VplOptions {
    /// Photons shot from all luminaires together (each leaves one VPL per reflection).
    pub photons: usize,
    /// Most reflections of a photon (1: the first bounce only).
    pub max_bounces: usize,
    /// Distance below which a VPL's 1/r² is held, metres.
    pub clamp_m: f64,
    /// Seed of the random numbers.
    pub seed: u64,
}

impl Default for VplOptions {
    fn default() -> Self {
        VplOptions {
            photons: 256,
            max_bounces: 8,
            clamp_m: 0.25,
            seed: 1,
        }
    }
}

/// A virtual point light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vpl {
    /// Position, scene metres (on the surface).
    pub position_m: DVec3,
    /// Unit normal of the side it lights.
    pub normal: DVec3,
    /// Reflected flux per channel, lm (its luminance-weighted Y is the flux in lm).
    pub flux_rgb_lm: [f64; 3],
    /// Reflections before it (1: first bounce).
    pub bounce: u32,
}

/// The VPLs of a scene and its luminaires.
#[derive(Debug, Clone, PartialEq)]
pub struct VplSet {
    /// The lights, in photon order.
    pub vpls: Vec<Vpl>,
    /// The clamp distance they are gathered with, metres.
    pub clamp_m: f64,
    /// The luminaires' flux as the emission tables give it, lm (what the photons carry in
    /// expectation).
    pub emitted_lm: f64,
}

/// One photometry's emission table: I at the centres of [`EMISSION_RINGS`] ×
/// [`EMISSION_SECTORS`] cells (1° × 1°, luminaire frame) and their cumulative flux I_c ΔΩ_c. Made once per photometry and shared by its placements.
#[derive(Debug, Clone, PartialEq)]
pub struct EmissionTable {
    cdf: Vec<f64>,
    cells: Vec<f64>,
    total_lm: f64,
}

const DTHETA: f64 = std::f64::consts::PI / EMISSION_RINGS as f64;
const DPHI: f64 = std::f64::consts::TAU / EMISSION_SECTORS as f64;

/// The z (cosine of the angle from +Z) at the ring edges `i` and `i + 1`, the larger first.
fn ring_z(i: usize) -> (f64, f64) {
    ((i as f64 * DTHETA).cos(), ((i + 1) as f64 * DTHETA).cos())
}

impl EmissionTable {
    /// The table of `p` (its absolute intensities).
    pub fn of(p: &Photometry) -> Self {
        let mut cells = Vec::with_capacity(EMISSION_RINGS * EMISSION_SECTORS);
        let mut cdf = Vec::with_capacity(EMISSION_RINGS * EMISSION_SECTORS);
        let mut acc = 0.0;
        for ring in 0..EMISSION_RINGS {
            let (z0, z1) = ring_z(ring);
            let d_omega = (z0 - z1) * DPHI;
            let z = ((ring as f64 + 0.5) * DTHETA).cos();
            for sector in 0..EMISSION_SECTORS {
                let d = cell_dir(z, (sector as f64 + 0.5) * DPHI);
                let i = p.web.sample_dir([d.x, d.y, d.z]);
                let i = if i.is_finite() && i > 0.0 { i } else { 0.0 };
                cells.push(i);
                acc += i * d_omega;
                cdf.push(acc);
            }
        }
        EmissionTable {
            cdf,
            cells,
            total_lm: acc,
        }
    }

    /// The flux the table gives, lm (Σ I_c ΔΩ).
    pub fn total_lm(&self) -> f64 {
        self.total_lm
    }
}

/// The direction (luminaire frame) at table coordinates: z = cos of the angle from +Z, φ about Z.
fn cell_dir(z: f64, phi: f64) -> DVec3 {
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

impl VplSet {
    /// Shoots `opts.photons` photons from `luminaires` through `scene` (its hierarchy `bvh`).
    ///
    /// Errors: the luminaires' matrices (argument `luminaires[i]`, as [`super::Tracer::new`]);
    /// photons 0 or more than [`MAX_PHOTONS`], max_bounces 0 or above 64, a clamp that is not
    /// finite and ≥ 0 (argument `options`).
    pub fn generate(scene: &Scene, bvh: &Bvh, luminaires: &[SceneLuminaire], opts: &VplOptions) -> Result<Self> {
        let mut distinct: Vec<(Arc<Photometry>, Arc<EmissionTable>)> = Vec::new();
        let tables: Vec<Arc<EmissionTable>> = luminaires
            .iter()
            .map(|l| {
                if let Some((_, t)) = distinct.iter().find(|(p, _)| Arc::ptr_eq(p, &l.photometry)) {
                    return t.clone();
                }
                let t = Arc::new(EmissionTable::of(&l.photometry));
                distinct.push((l.photometry.clone(), t.clone()));
                t
            })
            .collect();
        Self::generate_with(scene, bvh, luminaires, &tables, opts)
    }

    /// [`VplSet::generate`] with each luminaire's emission table given (`tables[i]` must be
    /// [`EmissionTable::of`] the photometry of `luminaires[i]`), so callers can keep them.
    ///
    /// Errors: those of [`VplSet::generate`]; a table count other than the luminaires' (argument
    /// `tables`).
    pub fn generate_with(
        scene: &Scene,
        bvh: &Bvh,
        luminaires: &[SceneLuminaire],
        tables: &[Arc<EmissionTable>],
        opts: &VplOptions,
    ) -> Result<Self> {
        if opts.photons == 0 || opts.photons > MAX_PHOTONS || opts.max_bounces == 0 || opts.max_bounces > 64 {
            return Err(SceneError::invalid(
                "options",
                format!(
                    "photons {} (1…{MAX_PHOTONS}) and max_bounces {} (1…64)",
                    opts.photons, opts.max_bounces
                ),
            ));
        }
        if !(opts.clamp_m.is_finite() && opts.clamp_m >= 0.0) {
            return Err(SceneError::invalid(
                "options",
                format!("clamp {} m must be finite and ≥ 0", opts.clamp_m),
            ));
        }
        if tables.len() != luminaires.len() {
            return Err(SceneError::invalid(
                "tables",
                format!("{} tables for {} luminaires", tables.len(), luminaires.len()),
            ));
        }
        let emitters = Emitter::prepare(luminaires)?;
        let totals: Vec<f64> = tables.iter().map(|t| t.total_lm).collect();
        let emitted_lm: f64 = totals.iter().sum();
        let mut set = VplSet {
            vpls: Vec::new(),
            clamp_m: opts.clamp_m,
            emitted_lm,
        };
        if !(emitted_lm.is_finite() && emitted_lm > 0.0) {
            return Ok(set);
        }
        let mut starts = Vec::with_capacity(totals.len());
        let mut acc = 0.0;
        for t in &totals {
            starts.push(acc);
            acc += t;
        }
        let off = offset_m(&scene.bounds());
        let n = opts.photons;
        let per_photon = emitted_lm / n as f64;
        let paths: Vec<Vec<Vpl>> = (0..n)
            .into_par_iter()
            .map(|k| {
                let mut rng = Pcg32::for_point(opts.seed, k as u64);
                let u = (k as f64 + 0.5) / n as f64 * emitted_lm;
                let l = starts.partition_point(|&s| s <= u).saturating_sub(1);
                let table = &tables[l];
                if table.total_lm <= 0.0 {
                    return Vec::new();
                }
                let within = (u - starts[l]).clamp(0.0, table.total_lm);
                let c = table.cdf.partition_point(|&s| s <= within).min(table.cells.len() - 1);
                let i_c = table.cells[c];
                if i_c <= 0.0 {
                    return Vec::new();
                }
                // Uniform in solid angle within the cell: z uniform between the ring's edges.
                let (ring, sector) = (c / EMISSION_SECTORS, c % EMISSION_SECTORS);
                let (z0, z1) = ring_z(ring);
                let z = z1 + (z0 - z1) * rng.next_f64();
                let phi = (sector as f64 + rng.next_f64()) * DPHI;
                let d_local = cell_dir(z, phi);
                let e = &emitters[l];
                let i_here = e.intensity_local(d_local);
                let flux = per_photon * i_here.max(0.0) / i_c;
                let (origin, dir) = e.emit(d_local, &mut rng);
                trace(scene, bvh, origin, dir, flux, opts.max_bounces, off, &mut rng)
            })
            .collect();
        set.vpls = paths.into_iter().flatten().collect();
        Ok(set)
    }

    /// The indirect illuminance (lx) at `x` with unit normal `n` from every VPL, and per channel
    /// (the light's colour after its reflections), by the gather of the module's docs.
    pub fn illuminance_rgb_lx(&self, x: DVec3, n: DVec3) -> [f64; 3] {
        let c2 = self.clamp_m * self.clamp_m;
        let mut e = [0.0; 3];
        for v in &self.vpls {
            let d = x - v.position_m;
            let r2 = d.length_squared();
            if r2 <= 0.0 {
                continue;
            }
            let r = r2.sqrt();
            let cos_v = v.normal.dot(d) / r;
            let cos_x = -n.dot(d) / r;
            if cos_v <= 0.0 || cos_x <= 0.0 {
                continue;
            }
            let g = cos_v * cos_x / (std::f64::consts::PI * r2.max(c2));
            for (ec, f) in e.iter_mut().zip(v.flux_rgb_lm) {
                *ec += f * g;
            }
        }
        e
    }

    /// The indirect illuminance (lx) at `x` with unit normal `n`: Y of
    /// [`VplSet::illuminance_rgb_lx`].
    pub fn illuminance_lx(&self, x: DVec3, n: DVec3) -> f64 {
        luminance_y(self.illuminance_rgb_lx(x, n))
    }

    /// Flux of the VPLs of each bounce, lm (index 0: first bounce).
    pub fn flux_by_bounce_lm(&self) -> Vec<f64> {
        let mut out = Vec::new();
        for v in &self.vpls {
            let b = v.bounce as usize;
            if out.len() < b {
                out.resize(b, 0.0);
            }
            out[b - 1] += luminance_y(v.flux_rgb_lm);
        }
        out
    }
}

/// Follows one photon of `flux` lm from `origin` along `dir`, leaving a VPL at every reflection.
#[allow(clippy::too_many_arguments)]
fn trace(
    scene: &Scene,
    bvh: &Bvh,
    mut origin: DVec3,
    mut dir: DVec3,
    flux: f64,
    max_bounces: usize,
    off: f64,
    rng: &mut Pcg32,
) -> Vec<Vpl> {
    let tris = scene.triangles();
    let mut out = Vec::new();
    let mut carried = [flux; 3];
    if !(flux.is_finite() && flux > 0.0) {
        return out;
    }
    for bounce in 1..=max_bounces {
        let Some(hit) = bvh.closest_hit(origin, dir, f64::INFINITY) else {
            break;
        };
        let t = tris[hit.triangle];
        let y = t[0] + hit.b1 * (t[1] - t[0]) + hit.b2 * (t[2] - t[0]);
        let mut ng = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        if ng == DVec3::ZERO {
            break;
        }
        if ng.dot(dir) > 0.0 {
            ng = -ng;
        }
        let rho = scene.reflectance_rgb(hit.triangle, hit.b1, hit.b2);
        let reflected = [carried[0] * rho[0], carried[1] * rho[1], carried[2] * rho[2]];
        if luminance_y(reflected) <= 0.0 {
            break;
        }
        out.push(Vpl {
            position_m: y,
            normal: ng,
            flux_rgb_lm: reflected,
            bounce: bounce as u32,
        });
        let q = luminance_y(rho).clamp(0.05, 0.95);
        if rng.next_f64() >= q {
            break;
        }
        carried = reflected.map(|f| f / q);
        origin = y + ng * off;
        dir = cosine_hemisphere(ng, rng.next_f64(), rng.next_f64());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::sample::box_triangles;
    use crate::scene::{Material, SceneParts};

    fn isotropic(cd: f64) -> Arc<crate::photometry::Photometry> {
        let text = format!("IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 3 1 1 2 0 0 0\n1 1 10\n0 90 180\n0\n{cd} {cd} {cd}\n");
        Arc::new(
            crate::photometry::load_from_text(&text, "iso.ies", &crate::photometry::LoadOptions::default()).unwrap(),
        )
    }

    fn closed_box(rho: f64) -> Scene {
        let tris = box_triangles(DVec3::new(-1.5, 0.0, -1.0), DVec3::new(1.5, 2.5, 1.0), true);
        let n = tris.len();
        Scene::new(SceneParts {
            triangles: tris,
            material_of: vec![0; n],
            uvs: vec![[[0.0; 2]; 3]; n],
            materials: vec![Material::grey(rho)],
            images: Vec::new(),
            warnings: Vec::new(),
        })
        .unwrap()
    }

    #[test]
    fn photons_carry_the_flux_and_bounces_fall_by_rho() {
        // Closed box, isotropic 100 cd source: Φ = 400π lm; bounce k reflects ρᵏ Φ in total.
        let scene = closed_box(0.5);
        let bvh = Bvh::build(&scene);
        let lum = SceneLuminaire {
            photometry: isotropic(100.0),
            scene_from_luminaire: crate::scene::placement(0.2, 1.3, -0.1, 0.0),
        };
        let set = VplSet::generate(
            &scene,
            &bvh,
            &[lum],
            &VplOptions {
                photons: 20_000,
                ..VplOptions::default()
            },
        )
        .unwrap();
        let phi = 400.0 * std::f64::consts::PI;
        assert!((set.emitted_lm / phi - 1.0).abs() < 1e-9, "{}", set.emitted_lm);
        let by = set.flux_by_bounce_lm();
        assert!(
            (by[0] / (0.5 * phi) - 1.0).abs() < 1e-9,
            "first bounce {} (every photon hits)",
            by[0]
        );
        assert!((by[1] / (0.25 * phi) - 1.0).abs() < 0.03, "second bounce {}", by[1]);
        // Every VPL lies on the box and faces inwards.
        assert!(set.vpls.iter().all(|v| {
            let p = v.position_m;
            p.x.abs() <= 1.5 + 1e-9 && p.z.abs() <= 1.0 + 1e-9 && (0.0..=2.5 + 1e-9).contains(&p.y)
        }));
        // In a closed box the indirect illuminance is close to ρΦ/(A(1 − ρ)) everywhere away from
        // the walls (the classic integrating-sphere result; exact for a sphere).
        let area = 2.0 * (3.0 * 2.0 + 3.0 * 2.5 + 2.0 * 2.5);
        let want = 0.5 * phi / (area * 0.5);
        let got = set.illuminance_lx(DVec3::new(0.0, 1.0, 0.0), DVec3::Y);
        assert!((got / want - 1.0).abs() < 0.15, "{got} vs {want}");
    }

    #[test]
    fn a_narrow_beam_sends_its_whole_flux() {
        // A 3° Gaussian spot (σ = 3°, nothing beyond 15°) into a white closed box: every photon
        // lands, so the first bounce holds the photometry's flux (within the photons' noise).
        let gammas: Vec<f64> = (0..=60)
            .map(|k| f64::from(k) * 0.25)
            .chain([20.0, 90.0, 180.0])
            .collect();
        let cd: Vec<String> = gammas
            .iter()
            .map(|g| {
                if *g <= 15.0 {
                    format!("{:.4}", 20000.0 * (-(g / 3.0).powi(2) / 2.0).exp())
                } else {
                    "0".to_string()
                }
            })
            .collect();
        let g: Vec<String> = gammas.iter().map(|g| format!("{g}")).collect();
        let text = format!(
            "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 {} 1 1 2 0 0 0\n1 1 10\n{}\n0\n{}\n",
            gammas.len(),
            g.join(" "),
            cd.join(" ")
        );
        let spot = Arc::new(
            crate::photometry::load_from_text(&text, "spot.ies", &crate::photometry::LoadOptions::default()).unwrap(),
        );
        let flux = spot.web.flux();
        let scene = closed_box(1.0);
        let bvh = Bvh::build(&scene);
        let lum = SceneLuminaire {
            photometry: spot,
            scene_from_luminaire: crate::scene::placement(0.0, 2.0, 0.0, 0.0),
        };
        let set = VplSet::generate(
            &scene,
            &bvh,
            &[lum],
            &VplOptions {
                photons: 4096,
                max_bounces: 1,
                ..VplOptions::default()
            },
        )
        .unwrap();
        assert!(
            (set.emitted_lm / flux - 1.0).abs() < 0.01,
            "table {} lm, web {flux} lm",
            set.emitted_lm
        );
        let first = set.flux_by_bounce_lm()[0];
        assert!((first / flux - 1.0).abs() < 0.01, "photons {first} lm, web {flux} lm");
        // No photon carries much more than its share: the weight I(ω)/I_c varies only as much as
        // the intensity does within a 1° cell (up to e^½ on this beam's flank at 9°; 1.86×
        // measured).
        let share = flux / 4096.0;
        let heaviest = set.vpls.iter().map(|v| luminance_y(v.flux_rgb_lm)).fold(0.0, f64::max);
        assert!(
            heaviest < 2.5 * share,
            "heaviest photon {heaviest} lm, share {share} lm"
        );
        // All of it lands under the spot (within 15° of the nadir at 2 m: 0.54 m).
        assert!(set
            .vpls
            .iter()
            .all(|v| v.position_m.y < 1e-9 && v.position_m.x.hypot(v.position_m.z) < 0.55));
    }

    #[test]
    fn bad_options_are_named() {
        let scene = closed_box(0.5);
        let bvh = Bvh::build(&scene);
        for o in [
            VplOptions {
                photons: 0,
                ..VplOptions::default()
            },
            VplOptions {
                max_bounces: 0,
                ..VplOptions::default()
            },
            VplOptions {
                clamp_m: f64::NAN,
                ..VplOptions::default()
            },
        ] {
            let e = VplSet::generate(&scene, &bvh, &[], &o).unwrap_err().to_string();
            assert!(e.contains("options"), "{e}");
        }
        let set = VplSet::generate(&scene, &bvh, &[], &VplOptions::default()).unwrap();
        assert!(set.vpls.is_empty() && set.emitted_lm == 0.0);
    }
}

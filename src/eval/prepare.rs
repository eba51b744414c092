//! The scan of one luminaire ([`Prepared`]): captures sized by the contract's pitch rule (capped, and
//! noted where capped), every tenth camera held out, the rest ray-cast and packed into the work
//! directory (a pack there with the same cameras is reused).

use std::sync::Arc;

use super::config::{
    angular_feature_deg, cameras_per_hemisphere, feature_px, lobe_exponent, smallest_feature_m, EvalConfig,
};
use super::EvalError;
use crate::nearfield::layout::Layout;
use crate::nearfield::pack::{write_pack, Pack, PackOptions};
use crate::nearfield::synth::{self, Luminaire, SynthOptions, SynthSource};
use crate::nearfield::{Camera, Intrinsics, RayImageSet, Scan};

/// The scan of one luminaire: pack, held-out cameras, pitch.
pub(super) struct Prepared {
    pub(super) lum: Arc<dyn Luminaire>,
    pub(super) pack: Arc<Pack>,
    pub(super) held_out: Vec<(Camera, Intrinsics)>,
    pub(super) pitch_m: f64,
    pub(super) view_pitch_m: f64,
    /// The smallest feature (m) and the view pixels across it, where the luminaire has one.
    pub(super) feature: Option<(f64, f64)>,
    /// The exponent n − 1 of a cosⁿ lobe's luminance, where the luminaire is one.
    pub(super) lobe: Option<f64>,
    pub(super) capture_px: u32,
    pub(super) per_hemisphere: usize,
    pub(super) rb: f64,
    pub(super) notes: Vec<String>,
}

pub(super) fn prepare(name: &str, cfg: &EvalConfig, progress: &dyn Fn(&str)) -> Result<Prepared, EvalError> {
    let lum: Arc<dyn Luminaire> = Arc::from(synth::luminaire(name)?);
    let b = lum.bounds();
    let rb = b.centre().length() + b.radius();
    let mut notes = Vec::new();
    let wanted = smallest_feature_m(name).map_or(0.002, |f| (f / feature_px(name)).min(0.002));
    let view_px = cfg.feature_view_px.unwrap_or(feature_px(name));
    // Image side that frames the bounding sphere at 80 % fill with this pitch at the centre.
    let alpha = (rb / cfg.radius_m).asin();
    let need_px = (2.0 * cfg.radius_m * alpha.tan() / (synth::scan::DEFAULT_FILL * wanted)).ceil() as u32;
    let capture_px = need_px.clamp(32, cfg.max_capture_px);
    if need_px > cfg.max_capture_px {
        notes.push(format!(
            "captures capped at {} px (the pitch rule asks {need_px} px)",
            cfg.max_capture_px
        ));
    }
    if cfg.capture_samples > 1 {
        notes.push(format!(
            "captures average {0} × {0} samples per pixel (the contract point-samples them)",
            cfg.capture_samples
        ));
    }
    if view_px != feature_px(name) && smallest_feature_m(name).is_some() {
        notes.push(format!(
            "views resolve the smallest feature with {view_px} px (the contract: {})",
            feature_px(name)
        ));
    }
    let per_hemisphere = cameras_per_hemisphere(name, cfg.per_hemisphere);
    if per_hemisphere != cfg.per_hemisphere {
        notes.push(format!(
            "{per_hemisphere} cameras per hemisphere (its {:.1}° lobe asks for ≤ 1/8 of it between cameras)",
            angular_feature_deg(name).unwrap_or(0.0)
        ));
    }
    let opts = SynthOptions {
        luminaire: name.into(),
        layout: Layout::Rigo {
            per_hemisphere,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        radius_m: cfg.radius_m,
        size: (capture_px, capture_px),
        ..SynthOptions::default()
    };
    let (_, set) = synth::synth_set(&opts)?;
    let pitch_m = cfg.radius_m / set.intrinsics.focal_px.x;
    // Views resolve the smallest feature with 6 pixels even where the capture cap does not.
    let view_pitch_m = smallest_feature_m(name).map_or(pitch_m, |f| pitch_m.min(f / view_px));
    // Hold out every tenth camera.
    let mut kept = Vec::new();
    let mut held_out = Vec::new();
    for (i, c) in set.cameras.iter().enumerate() {
        if i % 10 == 9 {
            held_out.push((c.clone(), *set.intrinsics_of(i)));
        } else {
            kept.push(c.clone());
        }
    }
    let kept_set = RayImageSet {
        sphere: set.sphere,
        intrinsics: set.intrinsics,
        cameras: kept,
    };
    std::fs::create_dir_all(&cfg.work_dir).map_err(|e| crate::nearfield::NearfieldError::io(&cfg.work_dir, e))?;
    let path = cfg.work_dir.join(if cfg.capture_samples > 1 {
        format!(
            "{name}-rigo{per_hemisphere}-{capture_px}px-{}x{0}.lvpack",
            cfg.capture_samples
        )
    } else {
        format!("{name}-rigo{per_hemisphere}-{capture_px}px.lvpack")
    });
    let reuse = Pack::open(&path)
        .ok()
        .filter(|p| p.image_count() == kept_set.cameras.len() && p.rayset().cameras == kept_set.cameras);
    let pack = match reuse {
        Some(p) => p,
        None => {
            progress(&format!(
                "{name}: scanning {} cameras at {capture_px}² px ({:.2} mm pitch) and packing",
                kept_set.cameras.len(),
                pitch_m * 1e3
            ));
            let source = SynthSource::new(lum.clone(), kept_set.clone(), cfg.capture_samples.max(1))?;
            let scan = Scan {
                set: kept_set,
                source: Box::new(source),
            };
            write_pack(&scan, &path, &PackOptions::default(), &|_, _| {})?;
            Pack::open(&path)?
        }
    };
    Ok(Prepared {
        lum,
        pack: Arc::new(pack),
        held_out,
        pitch_m,
        view_pitch_m,
        feature: smallest_feature_m(name).map(|f| (f, view_px)),
        lobe: lobe_exponent(name).map(|n| n - 1.0),
        capture_px,
        per_hemisphere,
        rb,
        notes,
    })
}

/// Side (px) of the captures a reconstructed proxy is made from: the scan's cameras rendered again at
/// most this large, with [`crate::nearfield::reconstruct::CAPTURE_SUPERSAMPLE`]² rays per pixel as a
/// sensor integrates (docs/proxy.md).
const RECONSTRUCT_PX: f64 = 256.0;

/// `k` scaled to at most [`RECONSTRUCT_PX`] on its longer side (the same field of view).
fn reconstruct_intrinsics(k: &Intrinsics) -> Intrinsics {
    let s = (RECONSTRUCT_PX / f64::from(k.width.max(k.height))).min(1.0);
    Intrinsics {
        width: ((f64::from(k.width) * s).round() as u32).max(1),
        height: ((f64::from(k.height) * s).round() as u32).max(1),
        principal_px: k.principal_px * s,
        focal_px: k.focal_px * s,
    }
}

/// A reconstructed proxy's triangles (`None` when none is kept) and notes: what was kept, or the
/// warnings saying why none was.
pub(super) type ReconstructedProxy = (Option<Vec<[f32; 3]>>, Vec<String>);

/// The proxy `lumiview pack --synth` would store for `p`'s scan: reconstructed from its cameras
/// ([`crate::nearfield::reconstruct::scan_proxy`]), as triangles; `None` with the warnings when
/// none is kept.
pub(super) fn reconstructed_proxy(p: &Prepared, progress: &dyn Fn(&str)) -> Result<ReconstructedProxy, EvalError> {
    let mut set = p.pack.rayset().clone();
    set.intrinsics = reconstruct_intrinsics(&set.intrinsics);
    for c in &mut set.cameras {
        c.intrinsics = c.intrinsics.as_ref().map(reconstruct_intrinsics);
    }
    progress(&format!(
        "{}: reconstructing the proxy from {} cameras",
        p.lum.name(),
        set.cameras.len()
    ));
    let source = SynthSource::new(
        p.lum.clone(),
        set.clone(),
        crate::nearfield::reconstruct::CAPTURE_SUPERSAMPLE,
    )?;
    let scan = Scan {
        set,
        source: Box::new(source),
    };
    let mut warnings = Vec::new();
    // The refinement reads the captures themselves where they are finer, cut to windows (rendered
    // as a sensor integrates, as the coarser ones are).
    let captures = p.pack.rayset();
    let window = |i: usize, crop: [u32; 4]| {
        let k = crate::nearfield::reconstruct::window_intrinsics(captures.intrinsics_of(i), crop);
        crate::nearfield::synth::render_pinhole(
            p.lum.as_ref(),
            &captures.cameras[i],
            &k,
            crate::nearfield::reconstruct::CAPTURE_SUPERSAMPLE,
        )
    };
    let finer = captures.intrinsics_of(0).width > scan.set.intrinsics_of(0).width;
    let fine = finer.then_some(crate::nearfield::reconstruct::FineImages {
        set: captures,
        window: &window,
    });
    let rec =
        crate::nearfield::reconstruct::scan_proxy_refined(&scan, fine, p.lum.name(), &|_, _, _| {}, &mut warnings)?;
    if let Some(r) = &rec {
        let rep = &r.report;
        warnings.push(format!(
            "continuous+rec-proxy: {}; it explains {:.1} % of the lit pixels (masks at {:.0e} of each image's maximum, carving 1s {:.0}°)",
            r.to_pack_proxy().source,
            rep.coverage * 100.0,
            rep.lit_relative,
            rep.grazing_deg
        ));
    }
    Ok((rec.map(|r| r.mesh.soup()), warnings))
}

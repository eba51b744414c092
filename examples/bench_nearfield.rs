//! Benchmark of the near-field pass, run by `scripts/bench-nearfield` (which prints the table).
//!
//! ```text
//! bench_nearfield [--luminaire star-panel] [--cameras 2000] [--capture-px 256]
//!                 [--size 640x360 ...] [--runs 25] [--work DIR]
//! ```
//!
//! A synthetic scan (`rigo` layout, N cameras per hemisphere, square captures) is packed (cached in
//! `--work`), uploaded, and drawn from an eye 1.6 m away that frames the luminaire so it covers most
//! of the frame. For each output size, in one process on one device: two trivial passes that write
//! a constant into every pixel of a target of the same size and format, submitted and waited for like
//! a frame (a render pass drawing one full-screen triangle, and a compute pass storing into a storage
//! texture, the notes' baseline), and a near-field frame in each mode (nearest, idw4 and continuous without proxy,
//! continuous with the proxy), each timed as the median of `--runs` (≥ 9) after one warm-up. Frame
//! times include the submission, the image's queue-family barriers and the wait for the GPU: what a
//! host pays per `lumi_render`. Prints one JSON object; ratios to the trivial pass are what to read
//! on a software device, absolute times only on a real GPU.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use glam::{DVec2, DVec3, Mat4};
use serde_json::json;

use lumiview::gpu::nearfield::{NearfieldOptions, NearfieldSettings};
use lumiview::gpu::renderer::Luminaire;
use lumiview::gpu::{
    ColorFormat, ContextDesc, DepthFormat, HostCamera, RenderOptions, RenderTarget, Renderer, TargetDesc,
};
use lumiview::nearfield::layout::Layout;
use lumiview::nearfield::pack::{csr_bytes_for, write_pack, Pack, PackOptions};
use lumiview::nearfield::proxy::triangles_of;
use lumiview::nearfield::select::SelectionMode;
use lumiview::nearfield::synth::{self, SynthOptions};
use lumiview::nearfield::{Camera, Intrinsics};

#[path = "common/bench.rs"]
mod bench;
use bench::{median_ms, plain_target, Res, Trivial, TrivialCompute};

struct Args {
    luminaire: String,
    cameras: usize,
    capture_px: u32,
    sizes: Vec<(u32, u32)>,
    runs: usize,
    work: PathBuf,
}

fn parse_args() -> Res<Args> {
    let mut a = Args {
        luminaire: "star-panel".into(),
        cameras: 2000,
        capture_px: 256,
        sizes: Vec::new(),
        runs: 25,
        work: std::env::temp_dir().join("lumiview-bench-nearfield"),
    };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut v = || it.next().ok_or_else(|| format!("{k} needs a value"));
        match k.as_str() {
            "--luminaire" => a.luminaire = v()?,
            "--cameras" => a.cameras = v()?.parse()?,
            "--capture-px" => a.capture_px = v()?.parse()?,
            "--runs" => a.runs = v()?.parse::<usize>()?.max(9),
            "--work" => a.work = PathBuf::from(v()?),
            "--size" => {
                let s = v()?;
                let (w, h) = s.split_once('x').ok_or_else(|| format!("--size {s}: expected WxH"))?;
                a.sizes.push((w.parse()?, h.parse()?));
            }
            _ => return Err(format!("unknown argument {k}").into()),
        }
    }
    if a.sizes.is_empty() {
        a.sizes.push((640, 360));
    }
    Ok(a)
}

fn run(a: &Args) -> Res<serde_json::Value> {
    std::fs::create_dir_all(&a.work)?;
    let path = a
        .work
        .join(format!("{}-rigo{}-{}px.lvpack", a.luminaire, a.cameras, a.capture_px));
    let opts = SynthOptions {
        luminaire: a.luminaire.clone(),
        layout: Layout::Rigo {
            per_hemisphere: a.cameras,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        size: (a.capture_px, a.capture_px),
        ..SynthOptions::default()
    };
    if Pack::open(&path).is_err() {
        eprintln!("packing {} ...", path.display());
        let scan = synth::synth_scan(&opts)?;
        write_pack(&scan, &path, &PackOptions::default(), &|_, _| {})?;
    }
    let pack = Arc::new(Pack::open(&path)?);
    let lum = synth::luminaire(&a.luminaire)?;
    // CSR of the same images (u32 column + f32 value per nonzero pixel, row pointers).
    let mut csr = 0u64;
    let mut nonzero = 0u64;
    for i in 0..pack.image_count() {
        let img = pack.decode_image(i)?;
        let nz = img.data.iter().filter(|v| **v != 0.0).count() as u64;
        nonzero += nz;
        csr += csr_bytes_for(img.height, nz);
    }
    let mut r = Renderer::new(&ContextDesc::default())?;
    let id = r.add_pack(
        pack.clone(),
        Some(triangles_of(&lum.proxy())),
        &NearfieldOptions::default(),
    )?;
    let mut inst = r.add_instance(id, Mat4::IDENTITY)?;
    let resident = match r.luminaire(id)? {
        Luminaire::Nearfield(n) => n.residency(),
        _ => return Err("not a near-field luminaire".into()),
    };
    let trivial = Trivial::new(&r.ctx.device);
    let b = lum.bounds();
    let centre = b.centre();
    let rb = b.radius();
    let mut sizes = Vec::new();
    for &(w, h) in &a.sizes {
        // Eye 1.6 m away at γ = 35°, the bounding sphere framed by the frame's height.
        let g = 35f64.to_radians();
        let eye = centre + DVec3::new(g.sin() * 0.6, g.sin() * 0.8, -g.cos()) * 1.6;
        let d = (centre - eye).length();
        let f = 0.5 * f64::from(h) / (rb / d).asin().tan();
        let cam = Camera::looking_at(eye, centre, "bench");
        let k = Intrinsics {
            width: w,
            height: h,
            principal_px: DVec2::new(0.5 * f64::from(w), 0.5 * f64::from(h)),
            focal_px: DVec2::splat(f),
        };
        let hc = HostCamera::from_pinhole(&cam, &k, 0.05, 10.0);
        let mut target = RenderTarget::new(
            &r.ctx,
            &TargetDesc {
                width: w,
                height: h,
                color: ColorFormat::Rgba32Float,
                depth: DepthFormat::None,
                exportable: false,
                semaphores: false,
            },
        )?;
        let plain_view = plain_target(&r, w, h);
        // Interleave: trivial, each mode, trivial again — drift on a shared machine shows up as two
        // different trivial medians.
        let trivial_compute = TrivialCompute::new(&r.ctx.device, w, h);
        let (c0, c0_runs) = median_ms(|| trivial_compute.frame(&r), a.runs)?;
        let (t0, t0_runs) = median_ms(|| trivial.frame(&r, &plain_view), a.runs)?;
        let mut modes = Vec::new();
        let all = [
            ("nearest", SelectionMode::Nearest, false),
            ("idw4", SelectionMode::Idw4, false),
            ("continuous", SelectionMode::Continuous, false),
            ("nearest+proxy", SelectionMode::Nearest, true),
            ("idw4+proxy", SelectionMode::Idw4, true),
            ("continuous+proxy", SelectionMode::Continuous, true),
        ];
        for (label, mode, proxy) in all {
            r.set_nearfield_settings(inst, NearfieldSettings { mode, proxy })?;
            let (m, runs) = median_ms(
                || {
                    r.render(&mut target, &hc, &RenderOptions::default())?;
                    Ok(())
                },
                a.runs,
            )?;
            let px = target.read(&r.ctx, lumiview::gpu::Attachment::Color)?;
            let lit = px
                .chunks_exact(16)
                .filter(|c| f32::from_le_bytes([c[12], c[13], c[14], c[15]]) > 0.0)
                .count();
            modes.push(json!({"mode": label, "median_ms": m, "runs_ms": runs,
                              "lit_fraction": lit as f64 / f64::from(w * h)}));
        }
        // Ratios from interleaved rounds: each round times both trivial passes and then every mode
        // once (after an untimed frame in the new setting). A mode's time is its median over the
        // rounds; a trivial pass's is the median of all its timings (the runs before the modes, one
        // per round, the runs after). On this shared machine the trivial compute pass alone has slow
        // phases (0.85 ms, then 1.5–2.6 ms for seconds at a time) that the modes do not show; a ratio
        // per round divided by whatever phase that round hit, and the median of ratios moved by 2×
        // between runs.
        let mut per_mode = vec![Vec::new(); all.len()];
        let (mut round_c, mut round_r) = (Vec::new(), Vec::new());
        let time = |f: &mut dyn FnMut() -> Res<()>| -> Res<f64> {
            let s = Instant::now();
            f()?;
            Ok(s.elapsed().as_secs_f64() * 1e3)
        };
        for _ in 0..a.runs {
            round_c.push(time(&mut || trivial_compute.frame(&r))?);
            round_r.push(time(&mut || trivial.frame(&r, &plain_view))?);
            for (k, (_, mode, proxy)) in all.iter().enumerate() {
                r.set_nearfield_settings(
                    inst,
                    NearfieldSettings {
                        mode: *mode,
                        proxy: *proxy,
                    },
                )?;
                r.render(&mut target, &hc, &RenderOptions::default())?;
                per_mode[k].push(time(&mut || {
                    r.render(&mut target, &hc, &RenderOptions::default())?;
                    Ok(())
                })?);
            }
        }
        let median = bench::median;
        // The frame's fixed cost: the same render call with the luminaire's instance removed.
        r.remove_instance(inst)?;
        let (empty, _) = median_ms(
            || {
                r.render(&mut target, &hc, &RenderOptions::default())?;
                Ok(())
            },
            a.runs,
        )?;
        inst = r.add_instance(id, Mat4::IDENTITY)?;
        let (t1, t1_runs) = median_ms(|| trivial.frame(&r, &plain_view), a.runs)?;
        let (c1, c1_runs) = median_ms(|| trivial_compute.frame(&r), a.runs)?;
        let trivial_c = median([c0_runs, round_c, c1_runs].concat());
        let trivial_r = median([t0_runs.clone(), round_r, t1_runs.clone()].concat());
        for (m, t) in modes.iter_mut().zip(per_mode) {
            let t = median(t);
            m["ratio_compute"] = json!(t / trivial_c);
            m["ratio_render"] = json!(t / trivial_r);
        }
        // Coverage: how much of the frame the luminaire's proxy fills.
        r.set_nearfield_settings(inst, NearfieldSettings::default())?;
        r.render(&mut target, &hc, &RenderOptions::default())?;
        let px = target.read(&r.ctx, lumiview::gpu::Attachment::Color)?;
        let covered = px
            .chunks_exact(16)
            .filter(|c| f32::from_le_bytes([c[12], c[13], c[14], c[15]]) > 0.0)
            .count();
        sizes.push(json!({
            "width": w, "height": h,
            "trivial_ms": [t0, t1], "trivial_runs_ms": [t0_runs, t1_runs],
            "trivial_compute_ms": [c0, c1],
            "modes": modes,
            "empty_frame_ms": empty,
            "covered_fraction": covered as f64 / f64::from(w * h),
        }));
    }
    Ok(json!({
        "device": r.ctx.caps.adapter_name,
        "is_cpu": r.ctx.caps.is_cpu,
        "luminaire": a.luminaire,
        "cameras": pack.image_count(),
        "capture_px": a.capture_px,
        "runs": a.runs,
        "pack_file_bytes": pack.file_len(),
        "gpu_resident_bytes": resident.gpu_bytes,
        "csr_bytes": csr,
        "nonzero_pixels": nonzero,
        "sizes": sizes,
    }))
}

fn main() -> ExitCode {
    let out = parse_args().and_then(|a| run(&a));
    match out {
        Ok(v) => {
            println!("{v}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("bench_nearfield: error: {e}");
            ExitCode::FAILURE
        }
    }
}

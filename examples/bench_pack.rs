//! Benchmark of the `.lvpack` store, run by `scripts/bench-pack` (which prints the table).
//!
//! ```text
//! bench_pack footprint  [--layout rigo:28000] [--images N] [--size 1216x1021] [--luminaire disc] [--noise SIGMA] --out FILE
//! bench_pack throughput --images N [--size 1216x1021] [--luminaire disc] --dir DIR
//! bench_pack reconstruct [--layout rigo:28000] [--images N] [--size 1216x1021] [--luminaire disc] [--noise SIGMA]
//! ```
//!
//! `footprint` renders a synthetic scan (the synthetic goniophotometer; `--images N` takes N cameras
//! spread evenly over the layout) and streams it into a pack; `throughput` writes N `.pf` files once
//! (manifest + images), then times a plain parallel read-and-sum pass over them, packing them from
//! the manifest, a second read pass and a CSR encoding pass; `reconstruct` reconstructs the proxy
//! of the same synthetic scan as `footprint` renders it, as `lumiview pack` does for a scan given
//! without one (`reconstruct::scan_proxy`, default options; the images it reads are rendered on
//! demand, as `footprint`'s are). `--noise SIGMA` adds Gaussian noise of SIGMA cd/m² to every pixel
//! of `footprint`'s and `reconstruct`'s images, clipped at zero, as a dark-corrected camera's carry it. Each prints one JSON object, with the process's peak resident
//! memory (VmHWM) at the end.

use std::error::Error;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use rayon::prelude::*;
use serde_json::json;

use lumiview::nearfield::error::Result as NfResult;
use lumiview::nearfield::images::read_image;
use lumiview::nearfield::layout::Layout;
use lumiview::nearfield::manifest::{load_scan, write_scan, ImportOptions};
use lumiview::nearfield::pack::{write_pack, CsrImage, PackOptions, PackStats};
use lumiview::nearfield::synth::{synth_scan, SynthOptions};
use lumiview::nearfield::{ImageSource, LuminanceImage, Scan};
use lumiview::scene::sampling::splitmix64;

type Res<T> = std::result::Result<T, Box<dyn Error>>;

/// The system allocator, counting the bytes held now and at most (what each stage of `reconstruct`
/// holds, apart from what the allocator keeps resident after it is freed).
struct Counting;

static HELD: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
static MOST: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

// SAFETY: every call is forwarded to the system allocator with the same layout.
unsafe impl std::alloc::GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: std::alloc::Layout) -> *mut u8 {
        use std::sync::atomic::Ordering::Relaxed;
        // SAFETY: forwarded as given.
        let p = unsafe { std::alloc::System.alloc(l) };
        if !p.is_null() {
            let now = HELD.fetch_add(l.size(), Relaxed) + l.size();
            MOST.fetch_max(now, Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, l: std::alloc::Layout) {
        HELD.fetch_sub(l.size(), std::sync::atomic::Ordering::Relaxed);
        // SAFETY: forwarded as given.
        unsafe { std::alloc::System.dealloc(p, l) }
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// Heap bytes held now and at most so far (MiB).
fn heap_mib() -> (f64, f64) {
    use std::sync::atomic::Ordering::Relaxed;
    let mib = |v: usize| v as f64 / 1048576.0;
    (mib(HELD.load(Relaxed)), mib(MOST.load(Relaxed)))
}

/// Every `k`-th camera of a scan, so a short run keeps the full layout's mix of views.
struct Subset {
    inner: Box<dyn ImageSource>,
    index: Vec<usize>,
}

impl ImageSource for Subset {
    fn image(&self, i: usize) -> NfResult<LuminanceImage> {
        self.inner.image(self.index[i])
    }
}

/// Gaussian noise of `sigma` cd/m² on every pixel (deterministic: a hash of camera and pixel),
/// clipped at zero, as a dark-corrected camera's images carry it into a pack (which takes no
/// negative luminance).
struct Noisy {
    inner: Box<dyn ImageSource>,
    sigma: f32,
}

impl ImageSource for Noisy {
    fn image(&self, i: usize) -> NfResult<LuminanceImage> {
        let mut img = self.inner.image(i)?;
        for (k, v) in img.data.iter_mut().enumerate() {
            *v = (*v + self.sigma * normal((i as u64) << 32 | k as u64)).max(0.0);
        }
        Ok(img)
    }
}

/// A standard normal deviate from a 64-bit key (SplitMix64, Box–Muller), as the tests draw it.
fn normal(key: u64) -> f32 {
    let uniform = |z: u64| (splitmix64(z) >> 11) as f64 / (1u64 << 53) as f64;
    let (u, v) = (uniform(2 * key).max(1e-300), uniform(2 * key + 1));
    ((-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()) as f32
}

fn subset(scan: Scan, n: Option<usize>) -> Scan {
    let total = scan.set.cameras.len();
    let Some(n) = n.filter(|&n| n < total && n > 0) else {
        return scan;
    };
    let index: Vec<usize> = (0..n).map(|i| i * total / n).collect();
    let mut set = scan.set;
    set.cameras = index.iter().map(|&i| set.cameras[i].clone()).collect();
    Scan {
        set,
        source: Box::new(Subset {
            inner: scan.source,
            index,
        }),
    }
}

struct Args {
    mode: String,
    layout: String,
    images: Option<usize>,
    size: (u32, u32),
    luminaire: String,
    noise: f32,
    out: Option<PathBuf>,
    dir: Option<PathBuf>,
}

fn parse_args() -> Res<Args> {
    let mut it = std::env::args().skip(1);
    let mode = it
        .next()
        .ok_or("usage: bench_pack footprint|throughput|reconstruct [options]")?;
    let mut a = Args {
        mode,
        layout: "rigo:28000".into(),
        images: None,
        size: (1216, 1021),
        luminaire: "disc".into(),
        noise: 0.0,
        out: None,
        dir: None,
    };
    while let Some(k) = it.next() {
        let v = it.next().ok_or_else(|| format!("{k} needs a value"))?;
        match k.as_str() {
            "--layout" => a.layout = v,
            "--images" => a.images = Some(v.parse()?),
            "--size" => {
                let (w, h) = v.split_once('x').ok_or("--size WxH")?;
                a.size = (w.parse()?, h.parse()?);
            }
            "--luminaire" => a.luminaire = v,
            "--noise" => a.noise = v.parse()?,
            "--out" => a.out = Some(v.into()),
            "--dir" => a.dir = Some(v.into()),
            _ => return Err(format!("unknown option {k}").into()),
        }
    }
    Ok(a)
}

fn layout(text: &str) -> Res<Layout> {
    let (kind, n) = text.split_once(':').ok_or("--layout KIND:N")?;
    let n: usize = n.parse()?;
    Ok(match kind {
        "rigo" => Layout::Rigo {
            per_hemisphere: n,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        "fibonacci" => Layout::Fibonacci { count: n },
        _ => return Err(format!("unknown layout {kind}").into()),
    })
}

fn synth(a: &Args) -> Res<Scan> {
    let opts = SynthOptions {
        luminaire: a.luminaire.clone(),
        layout: layout(&a.layout)?,
        size: a.size,
        ..SynthOptions::default()
    };
    let scan = subset(synth_scan(&opts)?, a.images);
    Ok(if a.noise > 0.0 {
        Scan {
            set: scan.set,
            source: Box::new(Noisy {
                inner: scan.source,
                sigma: a.noise,
            }),
        }
    } else {
        scan
    })
}

/// Peak resident set size of this process in KiB (VmHWM), 0 when unknown.
fn vm_hwm_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

fn stats_json(s: &PackStats, secs: f64) -> serde_json::Value {
    json!({
        "images": s.images, "tiles_kept": s.tiles_kept, "tiles_f32": s.tiles_f32, "pages": s.pages,
        "bytes": s.bytes, "pool_bytes": s.pool_bytes, "tile_table_bytes": s.tile_table_bytes,
        "pixels": s.pixels, "pixels_kept": s.pixels_kept,
        "dense_f16_bytes": s.dense_f16_bytes, "csr_bytes": s.csr_bytes,
        "ratio_to_dense_f16": s.ratio_to_dense_f16(), "ratio_to_csr": s.ratio_to_csr(),
        "peak_pending_images": s.peak_pending_images, "peak_pending_bytes": s.peak_pending_bytes,
        "pack_s": secs, "images_per_s": s.images as f64 / secs,
        "mpx_per_s": s.pixels as f64 / secs / 1e6,
    })
}

fn progress(label: &'static str) -> impl Fn(usize, usize) + Sync {
    move |done, total| {
        if done % 2000 == 0 || done == total {
            eprintln!("bench_pack: {label}: {done}/{total}");
        }
    }
}

fn footprint(a: &Args) -> Res<serde_json::Value> {
    let out = a.out.clone().ok_or("--out FILE")?;
    let scan = synth(a)?;
    let t = Instant::now();
    let stats = write_pack(&scan, &out, &PackOptions::default(), &progress("footprint"))?;
    let mut v = stats_json(&stats, t.elapsed().as_secs_f64());
    v["mode"] = json!("footprint");
    v["layout"] = json!(a.layout);
    v["noise_cd_m2"] = json!(a.noise);
    v["size"] = json!([a.size.0, a.size.1]);
    v["vm_hwm_kib"] = json!(vm_hwm_kib());
    v["heap_most_mib"] = json!(heap_mib().1);
    Ok(v)
}

fn reconstruct(a: &Args) -> Res<serde_json::Value> {
    let scan = synth(a)?;
    let (held, _) = heap_mib();
    eprintln!(
        "bench_pack: reconstruct: scan made (peak resident {:.0} MiB; heap {held:.1} MiB)",
        vm_hwm_kib() as f64 / 1024.0
    );
    let t = Instant::now();
    let last = std::sync::Mutex::new(Instant::now());
    let progress = |stage: &str, done: usize, total: usize| {
        let mut l = last.lock().unwrap_or_else(|e| e.into_inner());
        if done == total || done == 0 || l.elapsed().as_secs_f64() > 10.0 {
            *l = Instant::now();
            let (held, most) = heap_mib();
            eprintln!(
                "bench_pack: reconstruct: {stage} {done}/{total} (peak resident {:.0} MiB; heap {held:.1} MiB, at most {most:.1})",
                vm_hwm_kib() as f64 / 1024.0
            );
        }
    };
    let mut warnings = Vec::new();
    let rec = lumiview::nearfield::reconstruct::scan_proxy(&scan, &a.luminaire, &progress, &mut warnings)?;
    let secs = t.elapsed().as_secs_f64();
    let mut v = json!({
        "mode": "reconstruct", "layout": a.layout, "size": [a.size.0, a.size.1], "noise_cd_m2": a.noise,
        "images": scan.set.cameras.len(), "reconstruct_s": secs, "kept": rec.is_some(),
        "warnings": warnings, "vm_hwm_kib": vm_hwm_kib(), "heap_most_mib": heap_mib().1,
    });
    if let Some(r) = rec {
        let r = r.report;
        v["cameras_read"] = json!(r.cameras_read);
        v["seconds"] =
            json!({"masks": r.seconds[0], "carving": r.seconds[1], "mesh": r.seconds[2], "refining": r.seconds[3]});
        v["voxel_mm"] = json!(r.voxel_m * 1e3);
        v["triangles"] = json!(r.triangles);
        v["triangles_before_simplifying"] = json!(r.simplified.triangles_before);
        v["coverage"] = json!(r.coverage);
        v["mask_bytes"] = json!(r.mask_bytes);
    }
    Ok(v)
}

/// Reads every image in parallel and sums its pixels (the baseline pass).
fn read_pass(files: &[PathBuf]) -> Res<(f64, f64)> {
    let t = Instant::now();
    let sum = files
        .par_iter()
        .map(|f| Ok(read_image(f)?.data.iter().map(|&v| f64::from(v)).sum::<f64>()))
        .collect::<NfResult<Vec<f64>>>()?
        .into_iter()
        .sum::<f64>();
    Ok((t.elapsed().as_secs_f64(), sum))
}

fn throughput(a: &Args) -> Res<serde_json::Value> {
    let dir = a.dir.clone().ok_or("--dir DIR")?;
    let n = a.images.ok_or("--images N")?;
    let manifest = dir.join("manifest.json");
    let files: Vec<PathBuf> = {
        let images = dir.join("images");
        let mut f: Vec<PathBuf> = std::fs::read_dir(&images)
            .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).collect())
            .unwrap_or_default();
        f.retain(|p| p.extension().is_some_and(|e| e == "pf"));
        f.sort();
        if f.len() != n || !manifest.exists() {
            let _ = std::fs::remove_dir_all(&dir);
            let scan = synth(a)?;
            let t = Instant::now();
            write_scan(&dir, &scan, &progress("writing .pf files"))?;
            eprintln!("bench_pack: wrote {n} .pf files in {:.1} s", t.elapsed().as_secs_f64());
            return throughput(a);
        }
        f
    };
    let (read1, sum) = read_pass(&files)?;
    let scan = load_scan(std::slice::from_ref(&manifest), &ImportOptions::default())?;
    let out = dir.join("bench.lvpack");
    let t = Instant::now();
    let stats = write_pack(&scan, &out, &PackOptions::default(), &|_, _| {})?;
    let pack_s = t.elapsed().as_secs_f64();
    let (read2, _) = read_pass(&files)?;
    let t = Instant::now();
    let csr: usize = files
        .par_iter()
        .map(|f| Ok(CsrImage::encode(&read_image(f)?)?.byte_len()))
        .collect::<NfResult<Vec<usize>>>()?
        .into_iter()
        .sum();
    let csr_s = t.elapsed().as_secs_f64();
    let file_bytes: u64 = files
        .iter()
        .filter_map(|f| std::fs::metadata(f).ok())
        .map(|m| m.len())
        .sum();
    let read = read1.min(read2);
    let mut v = stats_json(&stats, pack_s);
    v["mode"] = json!("throughput");
    v["pf_bytes"] = json!(file_bytes);
    v["read_s"] = json!([read1, read2]);
    v["read_sum_cd_m2"] = json!(sum);
    v["pack_over_read"] = json!(pack_s / read);
    v["csr_encode_s"] = json!(csr_s);
    v["csr_bytes_encoded"] = json!(csr);
    v["threads"] = json!(rayon::current_num_threads());
    v["vm_hwm_kib"] = json!(vm_hwm_kib());
    if csr as u64 != stats.csr_bytes {
        return Err(format!("CSR encoder gives {csr} bytes, the pack counted {}", stats.csr_bytes).into());
    }
    Ok(v)
}

fn main() -> ExitCode {
    let run = || -> Res<()> {
        let a = parse_args()?;
        let v = match a.mode.as_str() {
            "footprint" => footprint(&a)?,
            "throughput" => throughput(&a)?,
            "reconstruct" => reconstruct(&a)?,
            m => return Err(format!("unknown mode {m}: footprint, throughput or reconstruct").into()),
        };
        println!("{v}");
        Ok(())
    };
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench_pack: error: {e}");
            ExitCode::FAILURE
        }
    }
}

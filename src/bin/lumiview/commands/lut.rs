//! `lumiview lut`: a look-up table of luminous intensity for host lighting (docs/lut-and-solid.md),
//! written as single-channel OpenEXR (f32, f16) or 8-bit grayscale PNG (u8, gamma 2.2).

use std::path::{Path, PathBuf};

use lumiview::photometry::lut::{Lut, LutEncoding, LutKind};

use super::{print_report, CliResult};

/// Which table to write.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum KindArg {
    /// Intensity over (C, γ); --size WxH (W C samples, H γ samples).
    #[value(name = "2d")]
    TwoD,
    /// Intensity averaged over C, over cos γ; --size N.
    #[value(name = "1d")]
    OneD,
}

/// Texel encoding.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum EncodingArg {
    /// 32-bit float (OpenEXR).
    F32,
    /// Half float (OpenEXR); absolute tables must stay below 65504 cd.
    F16,
    /// 8 bits, normalised, gamma 2.2 (PNG).
    U8,
}

/// Arguments of `lumiview lut`.
#[derive(clap::Args, Debug)]
pub struct LutArgs {
    /// IES or EULUMDAT file.
    pub file: PathBuf,
    /// Table kind.
    #[arg(long, value_enum, default_value = "2d")]
    pub kind: KindArg,
    /// Size: WxH for 2d (C samples × γ samples; default 360x181, 1° steps), N for 1d (default
    /// 1024).
    #[arg(long, value_name = "WxH|N")]
    pub size: Option<String>,
    /// Texel encoding: f32 or f16 need an .exr output, u8 a .png output.
    #[arg(long, value_enum, default_value = "f32")]
    pub encoding: EncodingArg,
    /// Divide by the table's maximum (always done for u8); the maximum in cd is stored beside.
    #[arg(long)]
    pub normalize: bool,
    /// Output file (.exr or .png).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub load: crate::LoadArgs,
}

/// Parses `--size` for the kind.
fn parse_size(text: Option<&str>, kind: KindArg) -> Result<(usize, usize), String> {
    let num = |s: &str| s.trim().parse::<usize>().ok();
    match (kind, text) {
        (KindArg::TwoD, None) => Ok((360, 181)),
        (KindArg::OneD, None) => Ok((1024, 1)),
        (KindArg::TwoD, Some(t)) => {
            let bad = || format!("--size `{t}`: a 2d table needs WxH (C samples x γ samples), e.g. 360x181");
            let (w, h) = t.split_once(['x', 'X', '×']).ok_or_else(bad)?;
            Ok((num(w).ok_or_else(bad)?, num(h).ok_or_else(bad)?))
        }
        (KindArg::OneD, Some(t)) => {
            let n = num(t).ok_or_else(|| format!("--size `{t}`: a 1d table needs a single number N, e.g. 1024"))?;
            Ok((n, 1))
        }
    }
}

/// Checks that the output extension fits the encoding.
fn check_extension(path: &Path, encoding: EncodingArg) -> Result<(), String> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let name = path.display();
    match (ext.as_deref(), encoding) {
        (Some("exr"), EncodingArg::F32 | EncodingArg::F16) | (Some("png"), EncodingArg::U8) => Ok(()),
        (Some("exr"), EncodingArg::U8) => Err(format!(
            "{name}: the u8 encoding is written as PNG; use a .png output or --encoding f32|f16"
        )),
        (Some("png"), _) => Err(format!(
            "{name}: float encodings are written as OpenEXR; use an .exr output or --encoding u8"
        )),
        _ => Err(format!(
            "{name}: unknown output extension; expected .exr (f32, f16) or .png (u8)"
        )),
    }
}

/// Runs `lumiview lut`.
pub fn lut(args: &LutArgs) -> CliResult {
    let (w, h) = parse_size(args.size.as_deref(), args.kind)?;
    check_extension(&args.output, args.encoding)?;
    let encoding = match args.encoding {
        EncodingArg::F32 => LutEncoding::F32,
        EncodingArg::F16 => LutEncoding::F16,
        EncodingArg::U8 => LutEncoding::U8,
    };
    let p = super::load(&args.file, &args.load)?;
    let at_file = |e: lumiview::photometry::PhotometryError| format!("{}: {e}", args.file.display());
    let table = match args.kind {
        KindArg::TwoD => Lut::new_2d(&p.web, w, h, args.normalize),
        KindArg::OneD => Lut::new_1d(&p.web, w, args.normalize),
    }
    .map_err(at_file)?;
    let encoded = table.encode(encoding).map_err(at_file)?;
    let bytes = match encoding {
        LutEncoding::U8 => encoded.to_png(),
        LutEncoding::F32 | LutEncoding::F16 => encoded.to_exr(),
    }
    .map_err(|e| format!("{}: {e}", args.output.display()))?;
    std::fs::write(&args.output, bytes).map_err(|e| format!("{}: cannot write file: {e}", args.output.display()))?;
    let what = match table.kind() {
        LutKind::Table2d => format!("2d table, {w} x {h} texels (C x gamma)"),
        LutKind::Table1d => format!("1d table, {w} texels over cos(gamma), C-averaged"),
    };
    let mut text = format!("wrote {}: {what}\nsource: {}\n", args.output.display(), p.source);
    for (key, value) in encoded.metadata() {
        text.push_str(&format!("{}: {value}\n", key.trim_start_matches("lumiview.")));
    }
    let pk = p.peak();
    let (peak, c, g) = (pk.cd, pk.c_deg, pk.gamma_deg);
    text.push_str(&format!("web_max_cd: {peak} (at C {c}, gamma {g})\n"));
    print_report(&text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes() {
        assert_eq!(parse_size(Some("64x32"), KindArg::TwoD), Ok((64, 32)));
        assert_eq!(parse_size(Some("64"), KindArg::OneD), Ok((64, 1)));
        assert!(parse_size(Some("64"), KindArg::TwoD).is_err());
        assert!(parse_size(Some("64x2"), KindArg::OneD).is_err());
        assert!(parse_size(Some("-3x2"), KindArg::TwoD).is_err());
    }

    #[test]
    fn extensions() {
        assert!(check_extension(Path::new("a.exr"), EncodingArg::F16).is_ok());
        assert!(check_extension(Path::new("a.PNG"), EncodingArg::U8).is_ok());
        assert!(check_extension(Path::new("a.png"), EncodingArg::F32).is_err());
        assert!(check_extension(Path::new("a.exr"), EncodingArg::U8).is_err());
        assert!(check_extension(Path::new("a.tif"), EncodingArg::F32).is_err());
        assert!(check_extension(Path::new("a"), EncodingArg::F32).is_err());
    }
}

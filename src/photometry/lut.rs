//! Look-up tables of luminous intensity for hosts that light their own scene (DESIGN §6).
//!
//! Two tables, both sampled from a [`PhotometricWeb`] in lumiview's luminaire frame (nadir γ = 0
//! along −Z, C0 along +X, C90 along +Y, C counter-clockwise seen from above):
//!
//! - **2D** over (C, γ), `width` C samples × `height` γ samples. Texel centres sit *on* the angles
//!   (node-aligned): texel `(i, j)` holds I(C = 360·i/W, γ = 180·j/(H − 1)), so row 0 is exactly the
//!   nadir and row H − 1 exactly the zenith. Sample with linear filtering, REPEAT in u (C is
//!   periodic) and CLAMP_TO_EDGE in v, at
//!   `u = C/360 + 0.5/W`, `v = (γ/180)·(H − 1)/H + 0.5/H`.
//! - **1D** over cos γ, `n` samples of the mean of I over the whole C circle:
//!   texel `i` holds the C-mean at cos γ = 1 − 2·i/(N − 1) (i = 0 nadir, i = N − 1 zenith).
//!   With a unit direction `d` of the luminaire frame, cos γ = −d.z and
//!   `u = ((1 + d.z)/2)·(N − 1)/N + 0.5/N`, CLAMP_TO_EDGE — no `acos`, no `atan`.
//!
//! Values are absolute (cd) or divided by the table's own maximum; the maximum (cd) travels beside
//! the table either way ([`Lut::max_cd`]). Encodings: f32, f16 and 8-bit with gamma-2.2 packing
//! (always normalised). `docs/lut-and-solid.md` has the shader code and the error bounds.

use std::f64::consts::PI;
use std::io::Cursor;

use half::f16;

use super::error::PhotometryError;
use super::web::PhotometricWeb;

/// Largest accepted table dimension (texels along one axis).
pub const MAX_LUT_SIZE: usize = 16384;

/// Largest accepted number of texels in one table (2²⁶, 256 MiB as f32).
pub const MAX_LUT_TEXELS: usize = 1 << 26;

/// Exponent of the 8-bit packing: `byte = round(255·x^(1/2.2))`, `x = (byte/255)^2.2`.
pub const U8_GAMMA: f64 = 2.2;

/// Bound on the 8-bit decoding error relative to the maximum: |I − decoded| ≤ this · I_max.
/// (The exact worst case is 1 − (254.5/255)^2.2 = 0.0043087, at the top of the range.)
pub const U8_MAX_ABS_ERROR: f64 = 0.004_31;

/// Bound on the relative f16 rounding error for normal half-floats (|x| ≥ 2⁻¹⁴): 2⁻¹¹.
pub const F16_MAX_REL_ERROR: f64 = 1.0 / 2048.0;

/// Bound on the absolute f16 rounding error below the normal range (|x| < 2⁻¹⁴): 2⁻²⁵.
pub const F16_MAX_SUBNORMAL_ERROR: f64 = 1.0 / 33_554_432.0;

/// Largest finite half-float; absolute tables above it cannot be stored as f16.
pub const F16_MAX: f64 = 65504.0;

/// The texel ↔ angle mapping of 2D tables, as stored in file metadata.
pub const MAPPING_2D: &str = "2d node-aligned: texel (i, j) centre at C = 360*i/W, gamma = 180*j/(H-1); \
     row 0 = nadir (gamma 0, -Z), column 0 = C0 (+X), C counter-clockwise seen from above (+Z); \
     sample with u = C/360 + 0.5/W (REPEAT), v = (gamma/180)*(H-1)/H + 0.5/H (CLAMP_TO_EDGE)";

/// The texel ↔ angle mapping of 1D tables, as stored in file metadata.
pub const MAPPING_1D: &str = "1d node-aligned over cos(gamma): texel i centre at cos(gamma) = 1 - 2*i/(N-1) \
     (i = 0 nadir, i = N-1 zenith), value = mean of I over the C circle; \
     with a unit luminaire-frame direction d, cos(gamma) = -d.z and \
     u = ((1 + d.z)/2)*(N-1)/N + 0.5/N (CLAMP_TO_EDGE)";

/// Which table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LutKind {
    /// Intensity over (C, γ): `width` C samples × `height` γ samples.
    Table2d,
    /// C-averaged intensity over cos γ: `width` samples, `height` = 1.
    Table1d,
}

impl LutKind {
    /// Short name used in metadata and on the command line: `2d` or `1d`.
    pub fn name(self) -> &'static str {
        match self {
            LutKind::Table2d => "2d",
            LutKind::Table1d => "1d",
        }
    }

    /// The texel ↔ angle mapping text ([`MAPPING_2D`] or [`MAPPING_1D`]).
    pub fn mapping(self) -> &'static str {
        match self {
            LutKind::Table2d => MAPPING_2D,
            LutKind::Table1d => MAPPING_1D,
        }
    }
}

/// How texels are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LutEncoding {
    /// 32-bit float, the value as is.
    F32,
    /// IEEE half float (relative error ≤ 2⁻¹¹; absolute tables must stay ≤ 65504 cd).
    F16,
    /// 8-bit, normalised, gamma-2.2 packed: `byte = round(255·(I/I_max)^(1/2.2))`.
    U8,
}

impl LutEncoding {
    /// Short name used in metadata: `f32`, `f16` or `u8-gamma2.2`.
    pub fn name(self) -> &'static str {
        match self {
            LutEncoding::F32 => "f32",
            LutEncoding::F16 => "f16",
            LutEncoding::U8 => "u8-gamma2.2",
        }
    }
}

/// A look-up table in f64, before encoding. Texel `(i, j)` is `values()[j * width + i]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Lut {
    kind: LutKind,
    width: usize,
    height: usize,
    normalized: bool,
    max_cd: f64,
    values: Vec<f64>,
}

/// Stored texels of an [`EncodedLut`], row-major like [`Lut::values`].
#[derive(Debug, Clone, PartialEq)]
pub enum LutTexels {
    /// [`LutEncoding::F32`] texels.
    F32(Vec<f32>),
    /// [`LutEncoding::F16`] texels.
    F16(Vec<f16>),
    /// [`LutEncoding::U8`] texels (gamma-2.2 packed, normalised).
    U8(Vec<u8>),
}

/// A look-up table in its storage encoding, with what a host needs to decode it.
#[derive(Debug, Clone, PartialEq)]
pub struct EncodedLut {
    kind: LutKind,
    width: usize,
    height: usize,
    normalized: bool,
    max_cd: f64,
    texels: LutTexels,
}

fn invalid(name: &'static str, message: impl Into<String>) -> PhotometryError {
    PhotometryError::InvalidArgument {
        name,
        message: message.into(),
    }
}

fn check_dim(name: &'static str, n: usize, min: usize) -> Result<(), PhotometryError> {
    if n < min || n > MAX_LUT_SIZE {
        return Err(invalid(name, format!("{n} texels: expected {min}…{MAX_LUT_SIZE}")));
    }
    Ok(())
}

/// Angles (C, γ) in degrees of the centre of texel `(i, j)` of a `width` × `height` 2D table:
/// C = 360·i/W, γ = 180·j/(H − 1). `height` must be ≥ 2 (for 1 the result is γ = 0).
pub fn texel_angles_2d(i: usize, j: usize, width: usize, height: usize) -> (f64, f64) {
    let c = 360.0 * i as f64 / width.max(1) as f64;
    let g = if height > 1 {
        180.0 * j as f64 / (height - 1) as f64
    } else {
        0.0
    };
    (c, g)
}

/// cos γ at the centre of texel `i` of an `n`-texel 1D table: 1 − 2·i/(N − 1) (1 for `n` < 2).
pub fn texel_cos_gamma_1d(i: usize, n: usize) -> f64 {
    if n < 2 {
        return 1.0;
    }
    1.0 - 2.0 * i as f64 / (n - 1) as f64
}

/// Texture coordinates of a luminaire-frame direction (need not be unit) in a 2D table, exactly as
/// the documented shader computes them: `u = C/360 + 0.5/W` (may lie outside 0…1: REPEAT),
/// `v = (γ/180)·(H − 1)/H + 0.5/H`. At the poles, where C is undefined, C = 0.
pub fn uv_2d(d: [f64; 3], width: usize, height: usize) -> [f64; 2] {
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(len.is_finite() && len > 0.0) {
        return [0.5 / width.max(1) as f64, 0.5 / height.max(1) as f64];
    }
    let cos_g = (-d[2] / len).clamp(-1.0, 1.0);
    let gamma = cos_g.acos();
    let c = if d[0] == 0.0 && d[1] == 0.0 {
        0.0
    } else {
        d[1].atan2(d[0])
    };
    let (w, h) = (width.max(1) as f64, height.max(1) as f64);
    let u = c / (2.0 * PI) + 0.5 / w;
    let v = (gamma / PI) * (h - 1.0) / h + 0.5 / h;
    [u, v]
}

/// Texture coordinate of a luminaire-frame direction (need not be unit) in an `n`-texel 1D table:
/// `u = ((1 + d.z)/2)·(N − 1)/N + 0.5/N` with `d` normalised (cos γ = −d.z).
pub fn u_1d(d: [f64; 3], n: usize) -> f64 {
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let n = n.max(1) as f64;
    if !(len.is_finite() && len > 0.0) {
        return 0.5 / n;
    }
    let z = (d[2] / len).clamp(-1.0, 1.0);
    ((1.0 + z) / 2.0) * (n - 1.0) / n + 0.5 / n
}

/// The true mean of I (cd) over the whole C circle at `gamma_deg`: the exact integral of the web's
/// piecewise-linear C interpolation, (1/360°)·∫ I(C, γ) dC. Zero outside the measured γ range.
pub fn c_mean(web: &PhotometricWeb, gamma_deg: f64) -> f64 {
    let cs = web.c_angles();
    let Some((&first, rest)) = cs.split_first() else {
        return 0.0;
    };
    let mut sum = 0.0;
    let mut prev = (first, web.sample(first, gamma_deg));
    for &c in rest {
        let v = web.sample(c, gamma_deg);
        sum += (c - prev.0) * 0.5 * (prev.1 + v);
        prev = (c, v);
    }
    sum / 360.0
}

/// Packs a normalised value (0…1, clamped) into a byte: `round(255·x^(1/2.2))`.
pub fn encode_u8(normalized: f64) -> u8 {
    if normalized.is_nan() || normalized <= 0.0 {
        return 0;
    }
    let x = normalized.min(1.0);
    (255.0 * x.powf(1.0 / U8_GAMMA)).round() as u8
}

/// Unpacks a gamma-2.2 byte: `max_cd·(byte/255)^2.2` (pass 1 for the normalised value).
pub fn decode_u8(byte: u8, max_cd: f64) -> f64 {
    max_cd * (f64::from(byte) / 255.0).powf(U8_GAMMA)
}

/// Unpacks a half float to f64 (exact).
pub fn decode_f16(h: f16) -> f64 {
    f64::from(h.to_f32())
}

/// Linear-filter taps along one axis, as a GPU samples: texel indices and the weight of the second.
fn taps(coord: f64, n: usize, repeat: bool) -> (usize, usize, f64) {
    let coord = if coord.is_finite() { coord } else { 0.0 };
    let x = coord * n as f64 - 0.5;
    let x0 = x.floor();
    let t = x - x0;
    let i0 = x0.clamp(-1e15, 1e15) as i64;
    let n = n as i64;
    let fix = |i: i64| {
        if repeat {
            i.rem_euclid(n) as usize
        } else {
            i.clamp(0, n - 1) as usize
        }
    };
    (fix(i0), fix(i0 + 1), t)
}

impl Lut {
    /// Samples the web into a `width` (C) × `height` (γ) table; texel `(i, j)` is
    /// `web.sample(360·i/W, 180·j/(H − 1))`, divided by the table's maximum if `normalize`.
    ///
    /// Errors: `width` outside 1…16384, `height` outside 2…16384, more than 2²⁶ texels, or
    /// `normalize` with an all-zero table.
    pub fn new_2d(web: &PhotometricWeb, width: usize, height: usize, normalize: bool) -> Result<Lut, PhotometryError> {
        check_dim("width", width, 1)?;
        check_dim("height", height, 2)?;
        if width * height > MAX_LUT_TEXELS {
            return Err(invalid(
                "size",
                format!(
                    "{width} × {height} = {} texels: at most {MAX_LUT_TEXELS}",
                    width * height
                ),
            ));
        }
        let mut values = Vec::with_capacity(width * height);
        for j in 0..height {
            for i in 0..width {
                let (c, g) = texel_angles_2d(i, j, width, height);
                values.push(web.sample(c, g));
            }
        }
        Lut::finish(LutKind::Table2d, width, height, normalize, values)
    }

    /// Samples the C-mean of the web into an `n`-texel table over cos γ; texel `i` is
    /// [`c_mean`] at cos γ = 1 − 2·i/(N − 1), divided by the table's maximum if `normalize`.
    ///
    /// Errors: `n` outside 2…16384, or `normalize` with an all-zero table.
    pub fn new_1d(web: &PhotometricWeb, n: usize, normalize: bool) -> Result<Lut, PhotometryError> {
        check_dim("size", n, 2)?;
        let values = (0..n)
            .map(|i| {
                let g = texel_cos_gamma_1d(i, n).clamp(-1.0, 1.0).acos().to_degrees();
                c_mean(web, g)
            })
            .collect();
        Lut::finish(LutKind::Table1d, n, 1, normalize, values)
    }

    fn finish(
        kind: LutKind,
        width: usize,
        height: usize,
        normalize: bool,
        mut values: Vec<f64>,
    ) -> Result<Lut, PhotometryError> {
        let max_cd = values.iter().copied().fold(0.0_f64, f64::max);
        if normalize {
            if max_cd.is_nan() || max_cd <= 0.0 {
                return Err(invalid(
                    "normalize",
                    "every intensity in the table is zero: nothing to normalise by",
                ));
            }
            for v in &mut values {
                *v /= max_cd;
            }
        }
        Ok(Lut {
            kind,
            width,
            height,
            normalized: normalize,
            max_cd,
            values,
        })
    }

    /// Which table this is.
    pub fn kind(&self) -> LutKind {
        self.kind
    }

    /// Texels along u (C samples for 2D, cos γ samples for 1D).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Texels along v (γ samples for 2D; 1 for 1D).
    pub fn height(&self) -> usize {
        self.height
    }

    /// Whether values are divided by [`Lut::max_cd`].
    pub fn normalized(&self) -> bool {
        self.normalized
    }

    /// The largest intensity in the table, cd (for 1D the largest C-mean). A 2D table's maximum
    /// can lie below the web's peak when no texel centre falls on it.
    pub fn max_cd(&self) -> f64 {
        self.max_cd
    }

    /// Texel values, `values()[j * width + i]`: cd, or relative to [`Lut::max_cd`] if normalised.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Texel `(i, j)` (`j` = 0 for 1D), or `None` outside the table.
    pub fn texel(&self, i: usize, j: usize) -> Option<f64> {
        if i >= self.width || j >= self.height {
            return None;
        }
        self.values.get(j * self.width + i).copied()
    }

    /// What a GPU returns for `(u, v)` with linear filtering (2D: REPEAT in u, CLAMP_TO_EDGE in
    /// v; 1D: CLAMP_TO_EDGE, `v` ignored), in the table's units.
    pub fn sample_uv(&self, u: f64, v: f64) -> f64 {
        let at = |i: usize, j: usize| self.values[j * self.width + i];
        match self.kind {
            LutKind::Table2d => {
                let (i0, i1, tu) = taps(u, self.width, true);
                let (j0, j1, tv) = taps(v, self.height, false);
                let a = at(i0, j0) * (1.0 - tu) + at(i1, j0) * tu;
                let b = at(i0, j1) * (1.0 - tu) + at(i1, j1) * tu;
                a * (1.0 - tv) + b * tv
            }
            LutKind::Table1d => {
                let (i0, i1, tu) = taps(u, self.width, false);
                at(i0, 0) * (1.0 - tu) + at(i1, 0) * tu
            }
        }
    }

    /// The documented shader path on the CPU: [`uv_2d`] or [`u_1d`] of a luminaire-frame
    /// direction, then [`Lut::sample_uv`]. Multiply by [`Lut::max_cd`] if normalised to get cd.
    pub fn sample_dir(&self, d: [f64; 3]) -> f64 {
        match self.kind {
            LutKind::Table2d => {
                let [u, v] = uv_2d(d, self.width, self.height);
                self.sample_uv(u, v)
            }
            LutKind::Table1d => self.sample_uv(u_1d(d, self.width), 0.0),
        }
    }

    /// Stores the table in `encoding`. 8-bit tables are always normalised (an absolute table is
    /// divided by its maximum first).
    ///
    /// Errors: f16 for an absolute table whose maximum exceeds 65504 cd (use a normalised table or
    /// f32); u8 for an all-zero table.
    pub fn encode(&self, encoding: LutEncoding) -> Result<EncodedLut, PhotometryError> {
        let (texels, normalized) = match encoding {
            LutEncoding::F32 => (
                LutTexels::F32(self.values.iter().map(|&v| v as f32).collect()),
                self.normalized,
            ),
            LutEncoding::F16 => {
                if !self.normalized && self.max_cd > F16_MAX {
                    return Err(invalid(
                        "encoding",
                        format!(
                            "the table peaks at {} cd, above the largest half float (65504): \
                             normalise it or use f32",
                            self.max_cd
                        ),
                    ));
                }
                (
                    LutTexels::F16(self.values.iter().map(|&v| f16::from_f64(v)).collect()),
                    self.normalized,
                )
            }
            LutEncoding::U8 => {
                if self.max_cd.is_nan() || self.max_cd <= 0.0 {
                    return Err(invalid(
                        "encoding",
                        "every intensity in the table is zero: 8-bit tables are normalised and \
                         there is nothing to normalise by",
                    ));
                }
                let d = if self.normalized { 1.0 } else { self.max_cd };
                (
                    LutTexels::U8(self.values.iter().map(|&v| encode_u8(v / d)).collect()),
                    true,
                )
            }
        };
        Ok(EncodedLut {
            kind: self.kind,
            width: self.width,
            height: self.height,
            normalized,
            max_cd: self.max_cd,
            texels,
        })
    }
}

impl EncodedLut {
    /// Which table this is.
    pub fn kind(&self) -> LutKind {
        self.kind
    }

    /// Texels along u.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Texels along v (1 for 1D).
    pub fn height(&self) -> usize {
        self.height
    }

    /// Whether stored values are relative to [`EncodedLut::max_cd`] (always for u8).
    pub fn normalized(&self) -> bool {
        self.normalized
    }

    /// The table's maximum intensity in cd (the decode scale of normalised tables).
    pub fn max_cd(&self) -> f64 {
        self.max_cd
    }

    /// The storage encoding.
    pub fn encoding(&self) -> LutEncoding {
        match self.texels {
            LutTexels::F32(_) => LutEncoding::F32,
            LutTexels::F16(_) => LutEncoding::F16,
            LutTexels::U8(_) => LutEncoding::U8,
        }
    }

    /// The stored texels, row-major (`[j * width + i]`).
    pub fn texels(&self) -> &LutTexels {
        &self.texels
    }

    /// Decoded values in the table's units (cd, or relative to the maximum if normalised).
    pub fn decode(&self) -> Vec<f64> {
        match &self.texels {
            LutTexels::F32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            LutTexels::F16(v) => v.iter().map(|&x| decode_f16(x)).collect(),
            LutTexels::U8(v) => v.iter().map(|&b| decode_u8(b, 1.0)).collect(),
        }
    }

    /// Decoded values in cd.
    pub fn decode_cd(&self) -> Vec<f64> {
        let k = if self.normalized { self.max_cd } else { 1.0 };
        self.decode().into_iter().map(|v| v * k).collect()
    }

    /// The metadata written into files (EXR header attributes, PNG tEXt chunks), as ASCII
    /// key/value pairs: `lumiview.kind`, `.size`, `.encoding`, `.normalized`, `.max_cd`, `.unit`,
    /// `.decode`, `.mapping`, `.frame`.
    pub fn metadata(&self) -> Vec<(&'static str, String)> {
        let size = match self.kind {
            LutKind::Table2d => format!("{}x{}", self.width, self.height),
            LutKind::Table1d => format!("{}", self.width),
        };
        let (unit, decode) = match (self.encoding(), self.normalized) {
            (LutEncoding::U8, _) => ("relative to lumiview.max_cd", "I_cd = max_cd * (byte/255)^2.2"),
            (_, true) => ("relative to lumiview.max_cd", "I_cd = value * max_cd"),
            (_, false) => ("cd", "I_cd = value"),
        };
        vec![
            ("lumiview.kind", self.kind.name().to_string()),
            ("lumiview.size", size),
            ("lumiview.encoding", self.encoding().name().to_string()),
            ("lumiview.normalized", self.normalized.to_string()),
            ("lumiview.max_cd", format!("{}", self.max_cd)),
            ("lumiview.unit", unit.to_string()),
            ("lumiview.decode", decode.to_string()),
            ("lumiview.mapping", self.kind.mapping().to_string()),
            (
                "lumiview.frame",
                "luminaire frame: gamma from nadir (-Z), C0 along +X, C90 along +Y, \
                 C counter-clockwise seen from above"
                    .to_string(),
            ),
        ]
    }

    /// The table as a single-channel (`Y`) OpenEXR file: f32 or f16 samples, ZIP compression,
    /// row 0 of the table = image row 0 (top). Metadata as header attributes: `lumiview.max_cd`
    /// as a `double`, the rest as `string`.
    ///
    /// Errors: an 8-bit table (use [`EncodedLut::to_png`]) or a failure of the EXR encoder.
    pub fn to_exr(&self) -> Result<Vec<u8>, PhotometryError> {
        use exr::prelude::*;
        let samples = match &self.texels {
            LutTexels::F32(v) => FlatSamples::F32(v.clone()),
            LutTexels::F16(v) => FlatSamples::F16(v.clone()),
            LutTexels::U8(_) => return Err(invalid("encoding", "8-bit tables are written as PNG, not OpenEXR")),
        };
        let mut attributes = LayerAttributes::default();
        for (key, value) in self.metadata() {
            let name = Text::new_or_none(key);
            let attr = if key == "lumiview.max_cd" {
                Some(AttributeValue::F64(self.max_cd))
            } else {
                Text::new_or_none(&value).map(AttributeValue::Text)
            };
            if let (Some(name), Some(attr)) = (name, attr) {
                attributes.other.insert(name, attr);
            }
        }
        attributes.software_name = Text::new_or_none("lumiview");
        let channels = AnyChannels::sort(SmallVec::from_vec(vec![AnyChannel::new("Y", samples)]));
        let layer = Layer::new(
            (self.width, self.height),
            attributes,
            Encoding::SMALL_LOSSLESS,
            channels,
        );
        let image = Image::from_layer(layer);
        let mut out = Cursor::new(Vec::new());
        image
            .write()
            .non_parallel()
            .to_buffered(&mut out)
            .map_err(|e| invalid("lut", format!("cannot encode OpenEXR: {e}")))?;
        Ok(out.into_inner())
    }

    /// The table as an 8-bit grayscale PNG (row 0 of the table = top row), metadata in tEXt
    /// chunks before the image data.
    ///
    /// Errors: a float table (use [`EncodedLut::to_exr`]) or a failure of the PNG encoder.
    pub fn to_png(&self) -> Result<Vec<u8>, PhotometryError> {
        let LutTexels::U8(bytes) = &self.texels else {
            return Err(invalid(
                "encoding",
                "float tables are written as OpenEXR, not PNG (PNG holds the 8-bit encoding)",
            ));
        };
        let png_err = |e: png::EncodingError| invalid("lut", format!("cannot encode PNG: {e}"));
        let (w, h) = (
            u32::try_from(self.width).map_err(|_| invalid("width", "too large"))?,
            u32::try_from(self.height).map_err(|_| invalid("height", "too large"))?,
        );
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, w, h);
            enc.set_color(png::ColorType::Grayscale);
            enc.set_depth(png::BitDepth::Eight);
            for (key, value) in self.metadata() {
                enc.add_text_chunk(key.to_string(), value).map_err(png_err)?;
            }
            let mut writer = enc.write_header().map_err(png_err)?;
            writer.write_image_data(bytes).map_err(png_err)?;
            writer.finish().map_err(png_err)?;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cos_web() -> PhotometricWeb {
        // I = 1000 cos γ (lower hemisphere) · (1 + 0.5 cos C), every 10°.
        let c: Vec<f64> = (0..=36).map(|i| i as f64 * 10.0).collect();
        let g: Vec<f64> = (0..=18).map(|i| i as f64 * 10.0).collect();
        let mut cd = Vec::new();
        for &ci in &c {
            for &gi in &g {
                let v = 1000.0 * gi.to_radians().cos().max(0.0) * (1.0 + 0.5 * ci.to_radians().cos());
                cd.push(v);
            }
        }
        PhotometricWeb::from_grid(c, g, cd).unwrap()
    }

    #[test]
    fn texel_centres_match_uv() {
        let (w, h) = (8, 5);
        for j in 0..h {
            for i in 0..w {
                let (c, g) = texel_angles_2d(i, j, w, h);
                let d = super::super::web::direction(c, g);
                let [u, v] = uv_2d(d, w, h);
                let centre_u = (i as f64 + 0.5) / w as f64;
                let centre_v = (j as f64 + 0.5) / h as f64;
                // u is periodic; the pole rows have C undefined.
                if j != 0 && j != h - 1 {
                    assert!(
                        ((u - centre_u).rem_euclid(1.0) + 1e-12).rem_euclid(1.0) < 1e-9,
                        "{i} {j} {u}"
                    );
                }
                assert!((v - centre_v).abs() < 1e-12, "{j} {v}");
            }
        }
        for i in 0..7 {
            let cg = texel_cos_gamma_1d(i, 7);
            let d = [(1.0 - cg * cg).max(0.0).sqrt(), 0.0, -cg];
            assert!((u_1d(d, 7) - (i as f64 + 0.5) / 7.0).abs() < 1e-12);
        }
    }

    #[test]
    fn c_mean_of_cos_modulation() {
        // The mean of 1 + 0.5 cos C over the circle is 1 (piecewise linear: exact at nodes' mean).
        let web = cos_web();
        let m = c_mean(&web, 0.0);
        assert!((m - 1000.0).abs() < 1e-6 * 1000.0, "{m}");
    }

    #[test]
    fn bad_sizes_are_errors() {
        let web = cos_web();
        assert!(Lut::new_2d(&web, 0, 10, false).is_err());
        assert!(Lut::new_2d(&web, 10, 1, false).is_err());
        assert!(Lut::new_2d(&web, 16385, 10, false).is_err());
        assert!(Lut::new_2d(&web, 16384, 16384, false).is_err());
        assert!(Lut::new_1d(&web, 1, false).is_err());
        assert!(Lut::new_1d(&web, 100_000, false).is_err());
        assert!(Lut::new_1d(&web, usize::MAX, false).is_err());
    }

    #[test]
    fn u8_round_trip_bound() {
        for k in 0..=10_000 {
            let x = k as f64 / 10_000.0;
            let d = decode_u8(encode_u8(x), 1.0);
            assert!((d - x).abs() <= U8_MAX_ABS_ERROR, "{x} {d}");
        }
        assert_eq!(encode_u8(1.0), 255);
        assert_eq!(encode_u8(0.0), 0);
        assert_eq!(encode_u8(f64::NAN), 0);
        assert_eq!(encode_u8(7.0), 255);
    }

    #[test]
    fn f16_overflow_is_an_error() {
        let c = vec![0.0, 360.0];
        let g = vec![0.0, 180.0];
        let web = PhotometricWeb::from_grid(c, g, vec![1e5, 1e5, 1e5, 1e5]).unwrap();
        let lut = Lut::new_1d(&web, 4, false).unwrap();
        assert!(lut.encode(LutEncoding::F16).is_err());
        let lut = Lut::new_1d(&web, 4, true).unwrap();
        assert!(lut.encode(LutEncoding::F16).is_ok());
    }

    #[test]
    fn zero_web_cannot_be_normalised() {
        let web = PhotometricWeb::from_grid(vec![0.0, 360.0], vec![0.0, 180.0], vec![0.0; 4]).unwrap();
        assert!(Lut::new_2d(&web, 4, 4, true).is_err());
        let lut = Lut::new_2d(&web, 4, 4, false).unwrap();
        assert!(lut.encode(LutEncoding::U8).is_err());
        assert!(lut.encode(LutEncoding::F32).is_ok());
    }

    #[test]
    fn subnormal_maximum_normalises_and_packs() {
        let web =
            PhotometricWeb::from_grid(vec![0.0, 360.0], vec![0.0, 180.0], vec![1e-310, 0.0, 1e-310, 0.0]).unwrap();
        let lut = Lut::new_1d(&web, 5, false).unwrap();
        let bytes = lut.encode(LutEncoding::U8).unwrap().decode();
        assert!(bytes.iter().all(|v| v.is_finite()));
        assert_eq!(bytes[0], 1.0);
        let lut = Lut::new_2d(&web, 4, 3, true).unwrap();
        assert!(lut.values().iter().all(|v| v.is_finite() && *v <= 1.0));
        assert_eq!(lut.values().iter().copied().fold(0.0, f64::max), 1.0);
    }

    #[test]
    fn gpu_emulation_wraps_c() {
        let web = cos_web();
        let lut = Lut::new_2d(&web, 36, 19, false).unwrap();
        // Between the last column (C = 350) and the first (C = 0 = 360).
        let d = super::super::web::direction(355.0, 40.0);
        let expect = web.sample(355.0, 40.0);
        assert!(
            (lut.sample_dir(d) - expect).abs() < 1e-9 * expect,
            "{} {expect}",
            lut.sample_dir(d)
        );
    }
}

//! Base-colour textures: decoded images and their sampling as linear diffuse reflectance.
//!
//! Promises:
//! - PNG images of any colour type and bit depth are decoded (palette and grey expanded, 16 bits
//!   reduced to 8) and kept as 8-bit sRGB-encoded RGB texels (alpha dropped: a diffuse reflectance
//!   has none). Images larger than [`MAX_TEXELS`] texels, or needing more than
//!   [`MAX_DECODE_BYTES`] to decode, are refused before their pixels are allocated.
//! - JPEG and other formats cannot be decoded here (no decoder among the vendored crates): the
//!   loader reports them as a warning and uses the material's factor alone
//!   (`scene::load`).
//! - Sampling follows glTF: UV (0, 0) is the image's top-left corner, u to the right, v down;
//!   texel centres at ((i + ½) / width, (j + ½) / height); `REPEAT`, `CLAMP_TO_EDGE` and
//!   `MIRRORED_REPEAT` per axis; the sampler's magnification filter picks nearest or bilinear.
//!   Texels are converted from sRGB to linear before filtering (glTF's base colour texture is
//!   sRGB-encoded; its factor is linear).

use std::io::Cursor;

/// Most texels in one image (8192 × 8192).
pub const MAX_TEXELS: u64 = 1 << 26;

/// Most bytes the PNG decoder may allocate for one image.
pub const MAX_DECODE_BYTES: usize = 1 << 28;

/// How texture coordinates outside 0…1 are mapped (glTF sampler `wrapS` / `wrapT`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrap {
    /// The image repeats (glTF's default).
    Repeat,
    /// Coordinates are clamped to the edge texels.
    ClampToEdge,
    /// The image repeats, every other copy mirrored.
    MirroredRepeat,
}

/// How a texture is read between texel centres (glTF sampler `magFilter`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Filter {
    /// The nearest texel.
    Nearest,
    /// Bilinear between the four nearest texels (the default when the sampler names none).
    Linear,
}

/// A decoded image: 8-bit sRGB-encoded RGB texels, rows from the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    width: u32,
    height: u32,
    texels: Vec<[u8; 3]>,
}

/// A material's base-colour texture: which image, which UV set, how it is sampled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureRef {
    /// Index into `Scene::images`.
    pub image: usize,
    /// The `TEXCOORD_n` set it reads.
    pub tex_coord: u32,
    /// Wrapping along u.
    pub wrap_s: Wrap,
    /// Wrapping along v.
    pub wrap_t: Wrap,
    /// Magnification filter.
    pub filter: Filter,
}

/// sRGB transfer function, linear value → 8-bit code (IEC 61966-2-1), the value clamped to 0…1
/// first (NaN gives 0).
pub fn linear_to_srgb8(c: f64) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// sRGB transfer function, 8-bit code → linear value in 0…1 (IEC 61966-2-1).
pub fn srgb_to_linear(code: u8) -> f64 {
    let c = f64::from(code) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Image {
    /// An image of `width` × `height` sRGB texels, rows from the top. `None` when the sizes do
    /// not match the texel count or either is zero.
    pub fn from_srgb(width: u32, height: u32, texels: Vec<[u8; 3]>) -> Option<Self> {
        let n = u64::from(width) * u64::from(height);
        (width > 0 && height > 0 && n == texels.len() as u64).then_some(Image { width, height, texels })
    }

    /// Decodes a PNG file's bytes.
    ///
    /// Errors: a message saying what is wrong (not a PNG, truncated, too large); the caller names
    /// the image.
    pub fn decode_png(bytes: &[u8]) -> Result<Self, String> {
        let mut decoder = png::Decoder::new_with_limits(
            Cursor::new(bytes),
            png::Limits {
                bytes: MAX_DECODE_BYTES,
            },
        );
        decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut reader = decoder.read_info().map_err(|e| format!("not a readable PNG: {e}"))?;
        let (width, height) = reader.info().size();
        if u64::from(width) * u64::from(height) > MAX_TEXELS {
            return Err(format!(
                "{width} × {height} texels is more than the {MAX_TEXELS} an image may have"
            ));
        }
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| format!("{width} × {height} texels do not fit in memory"))?;
        let mut buf = crate::files::try_vec::<u8>(size, "decoding a PNG image").map_err(|e| e.to_string())?;
        buf.resize(size, 0);
        let info = reader.next_frame(&mut buf).map_err(|e| format!("PNG data: {e}"))?;
        let channels = match info.color_type {
            png::ColorType::Grayscale => 1,
            png::ColorType::GrayscaleAlpha => 2,
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            png::ColorType::Indexed => return Err("palette not expanded".into()),
        };
        if info.bit_depth != png::BitDepth::Eight {
            return Err(format!("{:?} samples after expansion; expected 8 bits", info.bit_depth));
        }
        let row_bytes = info.line_size;
        let mut texels = crate::files::try_vec::<[u8; 3]>(width as usize * height as usize, "a PNG image's texels")
            .map_err(|e| e.to_string())?;
        for row in buf.chunks(row_bytes).take(height as usize) {
            for px in row.chunks_exact(channels).take(width as usize) {
                texels.push(match channels {
                    1 | 2 => [px[0]; 3],
                    _ => [px[0], px[1], px[2]],
                });
            }
        }
        Image::from_srgb(width, height, texels).ok_or_else(|| "PNG data shorter than its size".to_string())
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The linear RGB value (0…1 per channel) at texture coordinates (`u`, `v`) under `texture`'s
    /// wrapping and filter. Non-finite coordinates read the top-left texel.
    pub fn sample_linear(&self, u: f64, v: f64, texture: &TextureRef) -> [f64; 3] {
        // Far outside [0, 1] only the wrap matters; clamped so that texel indices stay far from
        // i64's range (a UV of 3e38 would overflow `x0 + 1`).
        const FAR: f64 = (1u64 << 40) as f64;
        let (u, v) = if u.is_finite() && v.is_finite() {
            (u.clamp(-FAR, FAR), v.clamp(-FAR, FAR))
        } else {
            (0.0, 0.0)
        };
        let x = u * f64::from(self.width) - 0.5;
        let y = v * f64::from(self.height) - 0.5;
        match texture.filter {
            Filter::Nearest => {
                // The texel containing (u, v): ⌊u · width⌋.
                let i = wrap((x + 0.5).floor() as i64, self.width, texture.wrap_s);
                let j = wrap((y + 0.5).floor() as i64, self.height, texture.wrap_t);
                self.linear_at(i, j)
            }
            Filter::Linear => {
                let (x0, y0) = (x.floor(), y.floor());
                let (tx, ty) = (x - x0, y - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let i0 = wrap(x0, self.width, texture.wrap_s);
                let i1 = wrap(x0 + 1, self.width, texture.wrap_s);
                let j0 = wrap(y0, self.height, texture.wrap_t);
                let j1 = wrap(y0 + 1, self.height, texture.wrap_t);
                let (a, b, c, d) = (
                    self.linear_at(i0, j0),
                    self.linear_at(i1, j0),
                    self.linear_at(i0, j1),
                    self.linear_at(i1, j1),
                );
                std::array::from_fn(|k| {
                    (a[k] * (1.0 - tx) + b[k] * tx) * (1.0 - ty) + (c[k] * (1.0 - tx) + d[k] * tx) * ty
                })
            }
        }
    }

    fn linear_at(&self, i: u32, j: u32) -> [f64; 3] {
        let t = self.texels[j as usize * self.width as usize + i as usize];
        t.map(|c| SRGB_TO_LINEAR[c as usize])
    }
}

/// A texel index in 0…n−1 of the (possibly out-of-range) index `i` under `mode`. `n` > 0.
fn wrap(i: i64, n: u32, mode: Wrap) -> u32 {
    let n = i64::from(n);
    let k = match mode {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n {
                m
            } else {
                2 * n - 1 - m
            }
        }
    };
    k as u32
}

/// [`srgb_to_linear`] for every 8-bit code.
static SRGB_TO_LINEAR: std::sync::LazyLock<[f64; 256]> =
    std::sync::LazyLock::new(|| std::array::from_fn(|c| srgb_to_linear(c as u8)));

#[cfg(test)]
mod tests {
    use super::*;

    fn tex(wrap: Wrap, filter: Filter) -> TextureRef {
        TextureRef {
            image: 0,
            tex_coord: 0,
            wrap_s: wrap,
            wrap_t: wrap,
            filter,
        }
    }

    fn encode(width: u32, height: u32, color: png::ColorType, data: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut enc = png::Encoder::new(&mut out, width, height);
        enc.set_color(color);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(data).unwrap();
        w.finish().unwrap();
        out
    }

    #[test]
    fn png_colour_types_decode_to_rgb() {
        let rgba = encode(2, 1, png::ColorType::Rgba, &[255, 0, 0, 10, 0, 128, 255, 255]);
        let img = Image::decode_png(&rgba).unwrap();
        assert_eq!((img.width(), img.height()), (2, 1));
        assert_eq!(img.texels, vec![[255, 0, 0], [0, 128, 255]]);
        let grey = encode(1, 2, png::ColorType::Grayscale, &[7, 200]);
        assert_eq!(Image::decode_png(&grey).unwrap().texels, vec![[7; 3], [200; 3]]);
        assert!(Image::decode_png(b"\x89PNG\r\n\x1a\nshort").is_err());
        assert!(Image::decode_png(&rgba[..rgba.len() - 20]).is_err());
    }

    #[test]
    fn srgb_transfer_matches_the_standard() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert!((srgb_to_linear(255) - 1.0).abs() < 1e-15);
        // 0.5 in sRGB is 0.2140 linear; the linear segment below 0.04045.
        assert!((srgb_to_linear(128) - 0.215_860_5).abs() < 1e-6);
        assert!((srgb_to_linear(10) - 10.0 / 255.0 / 12.92).abs() < 1e-15);
        // The encoder inverts the decoder for every code; out of range and NaN clamp.
        assert!((0..=255u8).all(|c| linear_to_srgb8(srgb_to_linear(c)) == c));
        assert_eq!(
            (linear_to_srgb8(-1.0), linear_to_srgb8(2.0), linear_to_srgb8(f64::NAN)),
            (0, 255, 0)
        );
    }

    #[test]
    fn sampling_wraps_and_filters_as_gltf_says() {
        // 2 × 1: left texel black, right white (sRGB 255 = linear 1).
        let img = Image::from_srgb(2, 1, vec![[0; 3], [255; 3]]).unwrap();
        let lin = tex(Wrap::Repeat, Filter::Linear);
        assert_eq!(img.sample_linear(0.25, 0.5, &lin), [0.0; 3], "texel centre");
        assert_eq!(img.sample_linear(0.75, 0.5, &lin), [1.0; 3]);
        assert!(
            (img.sample_linear(0.5, 0.5, &lin)[0] - 0.5).abs() < 1e-12,
            "halfway, linear space"
        );
        // Repeat: u = 1.25 is u = 0.25; between the last and first texel at u = 0 (x = -0.5).
        assert_eq!(img.sample_linear(1.25, 0.5, &lin), [0.0; 3]);
        assert!((img.sample_linear(0.0, 0.5, &lin)[0] - 0.5).abs() < 1e-12);
        let clamp = tex(Wrap::ClampToEdge, Filter::Linear);
        assert_eq!(img.sample_linear(0.0, 0.5, &clamp), [0.0; 3]);
        assert_eq!(img.sample_linear(7.0, 0.5, &clamp), [1.0; 3]);
        let mirror = tex(Wrap::MirroredRepeat, Filter::Nearest);
        assert_eq!(img.sample_linear(1.25, 0.5, &mirror), [1.0; 3], "mirrored copy");
        assert_eq!(img.sample_linear(2.25, 0.5, &mirror), [0.0; 3]);
        let near = tex(Wrap::Repeat, Filter::Nearest);
        assert_eq!(img.sample_linear(0.49, 0.5, &near), [0.0; 3]);
        assert_eq!(img.sample_linear(f64::NAN, 0.5, &near), [0.0; 3]);
        assert_eq!(wrap(-1, 4, Wrap::MirroredRepeat), 0);
        assert_eq!(wrap(-5, 4, Wrap::MirroredRepeat), 3);
    }
}

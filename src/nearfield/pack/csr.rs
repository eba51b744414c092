//! CSR (compressed sparse rows): the reference viewer's image layout, kept as the yardstick the
//! `.lvpack` footprint and access speed are measured against. Per image: `height + 1` row pointers
//! (`u32`), then a `u32` column index and an `f32` value per nonzero pixel, columns ascending within
//! a row. Lossless; a random read is a binary search within the row.

use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::LuminanceImage;

/// Bytes of the CSR layout of an image with `height` rows and `nonzero` stored pixels:
/// `4 · (height + 1) + 8 · nonzero`.
pub fn csr_bytes_for(height: u32, nonzero: u64) -> u64 {
    4 * (u64::from(height) + 1) + 8 * nonzero
}

/// Bytes the CSR layout of `image` takes (its nonzero pixels; see [`csr_bytes_for`]).
pub fn csr_bytes(image: &LuminanceImage) -> usize {
    let nonzero = image.data.iter().filter(|v| **v != 0.0).count();
    4 * (image.height as usize + 1) + 8 * nonzero
}

/// One image in CSR form.
#[derive(Debug, Clone, PartialEq)]
pub struct CsrImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `height + 1` offsets into `cols`/`values`: row `r` holds entries `row_ptr[r]..row_ptr[r + 1]`.
    pub row_ptr: Vec<u32>,
    /// Column of each stored pixel, ascending within its row.
    pub cols: Vec<u32>,
    /// Luminance (cd/m²) of each stored pixel.
    pub values: Vec<f32>,
}

/// Size of the serialised header: width, height, nonzero count (u32 each).
const HEADER: usize = 12;

impl CsrImage {
    /// Encodes the nonzero pixels of `image`. Fails when the pixel count does not match the size or
    /// more than `u32::MAX` pixels are nonzero (a u32 row pointer cannot address them).
    pub fn encode(image: &LuminanceImage) -> Result<Self> {
        let (w, h) = (image.width as usize, image.height as usize);
        if image.data.len() != w * h {
            return Err(NearfieldError::invalid(
                "csr image",
                "pixel count does not match width × height",
            ));
        }
        let mut row_ptr = Vec::with_capacity(h + 1);
        let (mut cols, mut values) = (Vec::new(), Vec::new());
        row_ptr.push(0u32);
        for r in 0..h {
            let row = &image.data[r * w..(r + 1) * w];
            for (c, &v) in row.iter().enumerate() {
                if v != 0.0 {
                    cols.push(c as u32);
                    values.push(v);
                }
            }
            let n = u32::try_from(cols.len())
                .map_err(|_| NearfieldError::invalid("csr image", "more than u32::MAX nonzero pixels"))?;
            row_ptr.push(n);
        }
        Ok(Self {
            width: image.width,
            height: image.height,
            row_ptr,
            cols,
            values,
        })
    }

    /// The dense image back (exact).
    pub fn decode(&self) -> LuminanceImage {
        let mut img = LuminanceImage::zeros(self.width, self.height);
        let w = self.width as usize;
        for r in 0..self.height as usize {
            let (a, b) = (self.row_ptr[r] as usize, self.row_ptr[r + 1] as usize);
            for (&c, &v) in self.cols[a..b].iter().zip(&self.values[a..b]) {
                img.data[r * w + c as usize] = v;
            }
        }
        img
    }

    /// The value at (col, row): a binary search within the row (0 outside the image).
    pub fn sample(&self, col: u32, row: u32) -> f32 {
        if col >= self.width || row >= self.height {
            return 0.0;
        }
        let (a, b) = (
            self.row_ptr[row as usize] as usize,
            self.row_ptr[row as usize + 1] as usize,
        );
        match self.cols[a..b].binary_search(&col) {
            Ok(i) => self.values[a + i],
            Err(_) => 0.0,
        }
    }

    /// Bytes of the layout (row pointers, columns, values; see [`csr_bytes_for`]).
    pub fn byte_len(&self) -> usize {
        4 * self.row_ptr.len() + 4 * self.cols.len() + 4 * self.values.len()
    }

    /// Serialises as little-endian `u32 width, u32 height, u32 nonzero`, then the row pointers,
    /// columns and values.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(HEADER + self.byte_len());
        out.extend_from_slice(&self.width.to_le_bytes());
        out.extend_from_slice(&self.height.to_le_bytes());
        out.extend_from_slice(&(self.cols.len() as u32).to_le_bytes());
        for p in &self.row_ptr {
            out.extend_from_slice(&p.to_le_bytes());
        }
        for c in &self.cols {
            out.extend_from_slice(&c.to_le_bytes());
        }
        for v in &self.values {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out
    }

    /// Reads [`CsrImage::to_bytes`] output back, checking sizes, monotone row pointers, ascending
    /// in-range columns and finite values ≥ 0.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let bad = |m: &str| NearfieldError::format("csr image", m.to_string());
        let u32_at = |i: usize| -> Option<u32> {
            let b = bytes.get(i..i + 4)?;
            Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        let (w, h, n) = match (u32_at(0), u32_at(4), u32_at(8)) {
            (Some(w), Some(h), Some(n)) => (w, h, n as usize),
            _ => return Err(bad("shorter than its 12-byte header")),
        };
        let need = (h as u64 + 1) * 4 + n as u64 * 8 + HEADER as u64;
        if bytes.len() as u64 != need {
            return Err(bad(&format!(
                "{} bytes, expected {need} for {h} rows and {n} pixels",
                bytes.len()
            )));
        }
        let words = |from: usize, count: usize| -> Vec<u32> {
            bytes[from..from + 4 * count]
                .chunks_exact(4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect()
        };
        let rows = h as usize + 1;
        let row_ptr = words(HEADER, rows);
        let cols = words(HEADER + 4 * rows, n);
        let values: Vec<f32> = words(HEADER + 4 * rows + 4 * n, n)
            .into_iter()
            .map(f32::from_bits)
            .collect();
        if row_ptr.first() != Some(&0) || row_ptr.last().map(|&l| l as usize) != Some(n) {
            return Err(bad("row pointers must start at 0 and end at the pixel count"));
        }
        for r in 0..h as usize {
            let (a, b) = (row_ptr[r] as usize, row_ptr[r + 1] as usize);
            if a > b || b > n {
                return Err(bad(&format!("row pointer of row {r} decreases or overruns")));
            }
            let row = &cols[a..b];
            if row.iter().any(|&c| c >= w) || row.windows(2).any(|p| p[0] >= p[1]) {
                return Err(bad(&format!(
                    "row {r}: columns must ascend and lie inside the width {w}"
                )));
            }
        }
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(bad(&format!("value {v} is not a finite luminance ≥ 0")));
        }
        Ok(Self {
            width: w,
            height: h,
            row_ptr,
            cols,
            values,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_size() {
        let mut img = LuminanceImage::zeros(7, 5);
        img.data[3] = 1.5;
        img.data[8] = 1e7;
        img.data[34] = 2e-6;
        let csr = CsrImage::encode(&img).unwrap();
        assert_eq!(csr.decode(), img);
        assert_eq!(csr.byte_len(), csr_bytes(&img));
        assert_eq!(csr_bytes(&img) as u64, csr_bytes_for(5, 3));
        assert_eq!(csr.sample(1, 1), 1e7);
        assert_eq!(csr.sample(2, 1), 0.0);
        assert_eq!(csr.sample(99, 1), 0.0);
        let bytes = csr.to_bytes();
        assert_eq!(CsrImage::from_bytes(&bytes).unwrap(), csr);
        for cut in 0..bytes.len() {
            assert!(CsrImage::from_bytes(&bytes[..cut]).is_err());
        }
        let mut bad = bytes.clone();
        bad[12 + 4 * 6 + 4] = 9; // column of the second pixel beyond the width
        assert!(CsrImage::from_bytes(&bad).is_err());
    }
}

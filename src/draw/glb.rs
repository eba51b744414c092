//! The glTF 2.0 binary container (GLB): one JSON chunk and one BIN chunk, the one writer behind the
//! photometric solid (`photometry::solid`) and the proxy meshes (`nearfield::synth::proxy`).

use serde_json::{json, Value};

/// `bufferView.target` of vertex data (`ARRAY_BUFFER`).
pub const ARRAY_BUFFER: u32 = 34962;
/// `bufferView.target` of indices (`ELEMENT_ARRAY_BUFFER`).
pub const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// The binary buffer of a GLB being built, with its buffer views.
#[derive(Debug, Default)]
pub struct Buffer {
    bin: Vec<u8>,
    views: Vec<Value>,
}

impl Buffer {
    /// An empty buffer.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends `data` as a buffer view on 4-byte alignment and returns the view's index.
    pub fn push_view(&mut self, data: &[u8], target: u32) -> usize {
        let i = self.push_data(data);
        self.views[i]["target"] = json!(target);
        i
    }

    /// Appends `data` as a buffer view without a `target` (what glTF asks of views that are not
    /// vertex or index data, such as an embedded image) and returns the view's index.
    pub fn push_data(&mut self, data: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": data.len()}));
        self.bin.extend_from_slice(data);
        self.views.len() - 1
    }

    /// The `bufferViews` array.
    pub fn views(&self) -> &[Value] {
        &self.views
    }

    /// The bytes so far (`buffers[0].byteLength` is their count).
    pub fn len(&self) -> usize {
        self.bin.len()
    }

    /// Whether nothing was pushed.
    pub fn is_empty(&self) -> bool {
        self.bin.is_empty()
    }

    /// The GLB file of the glTF document `doc` (which names this buffer as buffer 0): header, the
    /// JSON chunk padded with spaces and the BIN chunk padded with zeros to 4 bytes.
    ///
    /// Errors: the JSON cannot be encoded, or the file would exceed 4 GiB (GLB lengths are u32).
    pub fn into_glb(mut self, doc: &Value) -> Result<Vec<u8>, String> {
        let mut json_bytes = serde_json::to_vec(doc).map_err(|e| format!("cannot encode glTF JSON: {e}"))?;
        while json_bytes.len() % 4 != 0 {
            json_bytes.push(b' ');
        }
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let total = 12 + 8 + json_bytes.len() + 8 + self.bin.len();
        let too_big = || "the mesh is too large for a GLB file (4 GiB)".to_string();
        let total32 = u32::try_from(total).map_err(|_| too_big())?;
        let json_len = u32::try_from(json_bytes.len()).map_err(|_| too_big())?;
        let bin_len = u32::try_from(self.bin.len()).map_err(|_| too_big())?;
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&total32.to_le_bytes());
        out.extend_from_slice(&json_len.to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json_bytes);
        out.extend_from_slice(&bin_len.to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&self.bin);
        Ok(out)
    }
}

/// Checks a GLB file's 12-byte header (magic, version 2, a length of at least one chunk header
/// that the bytes hold) before the `gltf` crate reads it: its parser subtracts before it checks.
/// Text that is not GLB (a .gltf's JSON) passes unchanged.
pub fn check_header(bytes: &[u8]) -> std::result::Result<(), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(format!("truncated GLB header: {} bytes", bytes.len()));
    };
    if version != 2 {
        return Err(format!("GLB version {version}; only glTF 2.0 is supported"));
    }
    if (length as usize) < 20 || length as usize > bytes.len() {
        return Err(format!(
            "truncated GLB: its header says {length} bytes, the file has {}",
            bytes.len()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_are_aligned_and_the_container_is_well_formed() {
        let mut b = Buffer::new();
        assert_eq!(b.push_view(&[1, 2, 3], ARRAY_BUFFER), 0);
        assert_eq!(b.push_view(&[4; 8], ELEMENT_ARRAY_BUFFER), 1);
        assert_eq!(b.views()[1]["byteOffset"], 4, "the second view starts on 4 bytes");
        assert_eq!(b.views()[1]["target"], ELEMENT_ARRAY_BUFFER);
        assert_eq!(b.len(), 12);
        assert_eq!(b.push_data(&[9; 5]), 2);
        assert!(b.views()[2].get("target").is_none(), "an image's view has no target");
        assert_eq!(b.views()[2]["byteOffset"], 12);
        assert_eq!(b.len(), 17);
        let glb = b.into_glb(&json!({"asset": {"version": "2.0"}})).unwrap();
        assert_eq!(&glb[..4], b"glTF");
        assert_eq!(u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize, glb.len());
        let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        assert_eq!(json_len % 4, 0);
        assert_eq!(&glb[16..20], b"JSON");
        let bin_at = 20 + json_len;
        assert_eq!(u32::from_le_bytes(glb[bin_at..bin_at + 4].try_into().unwrap()), 20);
        assert_eq!(&glb[bin_at + 4..bin_at + 8], b"BIN\0");
        assert_eq!(glb.len() % 4, 0);
    }
}

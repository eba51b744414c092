//! Loading a glTF 2.0 scene (`.glb`, or `.gltf` with its buffers and images embedded as base64
//! data URIs or in files beside it) into a [`Scene`].
//!
//! Promises:
//! - glTF's coordinates are kept: metres, +Y up. Every mesh primitive of every node of the default
//!   scene (else the first scene, else every root node) is taken with its node's world transform
//!   (the hierarchy's matrices multiplied down from the root; a mirroring transform keeps the
//!   winding consistent). Triangle lists, strips and fans are read; points and lines carry no
//!   surface and are skipped with a warning.
//! - A material's reflectance is its `baseColorFactor` (linear RGB; alpha, metallic and roughness
//!   are not used: every surface is Lambertian) times its `baseColorTexture` when that is a PNG,
//!   read through the texture's sampler and `TEXCOORD_n` set ([`super::texture`]). A JPEG (or other)
//!   texture cannot be decoded with the vendored crates: a warning names it and the factor alone is
//!   used. A primitive without a material gets glTF's default material, white (ρ = 1), with a
//!   warning, as the specification says.
//! - Hostile files give errors naming the file and the glTF object, never a panic and never an
//!   allocation their size does not justify: the file (and each buffer or image file it names) is
//!   read with a size limit ([`MAX_SCENE_BYTES`]) through [`crate::files`]; the GLB header is
//!   checked before `gltf` sees it; accessors are read here, not by `gltf`'s reader, with every
//!   offset, stride and count checked against its buffer view and buffer; indices are checked
//!   against the vertex count; positions and transforms must be finite; triangles are limited to
//!   [`super::model::MAX_TRIANGLES`]; a node reached twice (a cycle, or two parents, which glTF
//!   forbids) is an error. Sparse accessors, quantized positions and URIs with a scheme other than
//!   `data:` are refused as unsupported.

use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3};
use gltf::accessor::{DataType, Dimensions};

use super::error::{Result, SceneError};
use super::model::{Material, Scene, SceneParts, MAX_TRIANGLES};
use super::texture::{Filter, Image, TextureRef, Wrap};

/// Largest glTF file, and largest buffer or image file it names, in bytes (1 GiB).
pub const MAX_SCENE_BYTES: u64 = 1 << 30;

/// Most bytes all buffers together may hold (2 GiB).
pub const MAX_TOTAL_BUFFER_BYTES: u64 = 2 << 30;

/// Most vertices all of a scene's nodes may read together, each instance of a mesh counted (four
/// times the vertices of the largest scene's triangles).
pub const MAX_VERTICES_READ: u64 = 4 * 3 * MAX_TRIANGLES as u64;

/// Most texels all of a scene's decoded images may hold together (3 bytes each: 768 MiB).
pub const MAX_SCENE_TEXELS: u64 = 1 << 28;

/// Loads the glTF scene at `path` ([`load_from_slice`] with the file's folder for its relative
/// URIs).
///
/// Errors: I/O ([`SceneError::Io`] naming the file, or the buffer or image file it names), and
/// every format error of [`load_from_slice`].
pub fn load(path: &Path) -> Result<Scene> {
    let bytes =
        crate::files::read_regular(path, MAX_SCENE_BYTES, "a glTF scene").map_err(|e| SceneError::io(path, e))?;
    let base = path.parent().unwrap_or(Path::new("."));
    load_from_slice(&bytes, path, Some(base))
}

/// Loads a glTF scene from its bytes. `path` names it in messages; `base_dir` is where relative
/// buffer and image URIs are looked for (`None`: only embedded data is allowed).
///
/// Errors ([`SceneError::Format`] naming `path` and the glTF object): not glTF 2.0, a truncated
/// GLB, a buffer or image missing or too short, accessors out of their views, indices out of
/// range, non-finite positions or transforms, an unreadable PNG texture, unsupported features
/// (sparse accessors, quantized positions, URIs with a scheme other than `data:`), too many
/// triangles, a node hierarchy that is not a forest, no triangles.
pub fn load_from_slice(bytes: &[u8], path: &Path, base_dir: Option<&Path>) -> Result<Scene> {
    let bad = |m: String| SceneError::format(path, m);
    crate::draw::glb::check_header(bytes).map_err(bad)?;
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| bad(format!("not a glTF 2.0 file: {e}")))?;
    let mut loader = Loader {
        path,
        base_dir,
        buffers: Vec::new(),
        warnings: Vec::new(),
        texels: 0,
        vertices_read: std::cell::Cell::new(0),
    };
    loader.read_buffers(&gltf)?;
    let (mut materials, images) = loader.read_materials(&gltf)?;
    let mut parts = SceneParts {
        images,
        ..Default::default()
    };
    let mut default_material: Option<u32> = None;

    let roots: Vec<gltf::Node> = match gltf.default_scene().or_else(|| gltf.scenes().next()) {
        Some(s) => s.nodes().collect(),
        None => {
            let mut is_child = vec![false; gltf.nodes().len()];
            for n in gltf.nodes() {
                for c in n.children() {
                    if let Some(f) = is_child.get_mut(c.index()) {
                        *f = true;
                    }
                }
            }
            gltf.nodes()
                .filter(|n| !is_child.get(n.index()).copied().unwrap_or(false))
                .collect()
        }
    };
    let mut stack: Vec<(gltf::Node, DMat4)> = roots.into_iter().rev().map(|n| (n, DMat4::IDENTITY)).collect();
    // glTF's hierarchy is a forest: a node reached twice has two parents or lies on a cycle.
    let mut visited = vec![false; gltf.nodes().len()];
    while let Some((node, parent)) = stack.pop() {
        match visited.get_mut(node.index()) {
            Some(v) if !*v => *v = true,
            _ => {
                return Err(bad(format!(
                    "node {} is reached twice: the node hierarchy has a cycle or a node with two parents",
                    node.index()
                )))
            }
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if !world.is_finite() {
            return Err(bad(format!("node {}: its transform is not finite", node.index())));
        }
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
                if !is_surface(prim.mode()) {
                    // A warning, not an error: such primitives are often helpers (outlines, markers).
                    loader.warnings.push(format!(
                        "{}: {what} draws {:?}, which have no surface; skipped",
                        path.display(),
                        prim.mode()
                    ));
                    continue;
                }
                let material = match prim.material().index() {
                    Some(i) => i as u32,
                    None => *default_material.get_or_insert_with(|| {
                        loader.warnings.push(format!(
                            "{}: a primitive has no material; glTF's default material is white (ρ = 1)",
                            path.display()
                        ));
                        materials.push(Material::grey(1.0));
                        (materials.len() - 1) as u32
                    }),
                };
                let tex_coord = materials
                    .get(material as usize)
                    .and_then(|m| m.base_color_texture)
                    .map(|t| t.tex_coord);
                loader.read_primitive(&prim, &what, world, material, tex_coord, &mut parts)?;
            }
        }
        for c in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((c, world));
        }
    }
    if parts.triangles.is_empty() {
        return Err(bad("no triangles in the scene".into()));
    }
    parts.materials = materials;
    parts.warnings = loader.warnings;
    Scene::new(parts).map_err(|e| bad(e.to_string()))
}

struct Loader<'p> {
    path: &'p Path,
    base_dir: Option<&'p Path>,
    buffers: Vec<Vec<u8>>,
    warnings: Vec<String>,
    /// Texels of the images decoded so far (against [`MAX_SCENE_TEXELS`]).
    texels: u64,
    /// Vertices read so far, every instance of a mesh counted (against [`MAX_VERTICES_READ`]).
    vertices_read: std::cell::Cell<u64>,
}

/// An accessor's bytes and layout, checked: element `i`'s component `k` lies within `bytes`.
struct AccessorData<'a> {
    bytes: &'a [u8],
    stride: usize,
    count: usize,
    component: DataType,
    dims: usize,
    normalized: bool,
}

impl AccessorData<'_> {
    fn component(&self, i: usize, k: usize) -> f64 {
        let at = i * self.stride + k * self.component.size();
        let b = &self.bytes[at..at + self.component.size()];
        let raw = match self.component {
            DataType::I8 => f64::from(b[0] as i8),
            DataType::U8 => f64::from(b[0]),
            DataType::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            DataType::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            DataType::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            DataType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        };
        if !self.normalized {
            return raw;
        }
        match self.component {
            DataType::I8 => (raw / 127.0).max(-1.0),
            DataType::U8 => raw / 255.0,
            DataType::I16 => (raw / 32767.0).max(-1.0),
            DataType::U16 => raw / 65535.0,
            _ => raw,
        }
    }

    fn index(&self, i: usize) -> u32 {
        let at = i * self.stride;
        let b = &self.bytes[at..at + self.component.size()];
        match self.component {
            DataType::U8 => u32::from(b[0]),
            DataType::U16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        }
    }
}

impl Loader<'_> {
    fn bad(&self, m: String) -> SceneError {
        SceneError::format(self.path, m)
    }

    /// Reads a file a URI names, beside the scene.
    fn read_uri_file(&self, uri: &str, what: &str) -> Result<Vec<u8>> {
        let Some(base) = self.base_dir else {
            return Err(self.bad(format!(
                "{what} refers to the file \"{uri}\", but the scene was given as bytes"
            )));
        };
        let rel = percent_decode(uri).ok_or_else(|| self.bad(format!("{what}: bad URI \"{uri}\"")))?;
        if has_uri_scheme(uri) || Path::new(&rel).is_absolute() {
            return Err(self.bad(format!(
                "{what}: URI \"{uri}\" is not a relative file name; unsupported"
            )));
        }
        let file: PathBuf = base.join(rel);
        crate::files::read_regular(&file, MAX_SCENE_BYTES, "a glTF buffer or image")
            .map_err(|e| SceneError::io(&file, e))
    }

    fn read_buffers(&mut self, gltf: &gltf::Gltf) -> Result<()> {
        let mut total = 0u64;
        for b in gltf.buffers() {
            let what = format!("buffer {}", b.index());
            let data = match b.source() {
                gltf::buffer::Source::Bin => gltf
                    .blob
                    .clone()
                    .ok_or_else(|| self.bad(format!("{what} refers to a GLB binary chunk the file lacks")))?,
                gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                    Some(rest) => {
                        decode_data_uri(rest).ok_or_else(|| self.bad(format!("{what}: bad base64 data URI")))?
                    }
                    None => self.read_uri_file(uri, &what)?,
                },
            };
            if data.len() < b.length() {
                return Err(self.bad(format!(
                    "{what} holds {} bytes, fewer than the {} it declares",
                    data.len(),
                    b.length()
                )));
            }
            total += data.len() as u64;
            if total > MAX_TOTAL_BUFFER_BYTES {
                return Err(self.bad(format!("buffers hold more than {MAX_TOTAL_BUFFER_BYTES} bytes")));
            }
            self.buffers.push(data);
        }
        Ok(())
    }

    /// The bytes of a buffer view, checked against its buffer.
    fn view_bytes(&self, view: &gltf::buffer::View, what: &str) -> Result<&[u8]> {
        let buffer = self
            .buffers
            .get(view.buffer().index())
            .ok_or_else(|| self.bad(format!("{what}: buffer {} is missing", view.buffer().index())))?;
        let end = view.offset().checked_add(view.length());
        end.and_then(|end| buffer.get(view.offset()..end)).ok_or_else(|| {
            self.bad(format!(
                "{what}: buffer view {} (bytes {} + {}) lies beyond buffer {} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                buffer.len()
            ))
        })
    }

    /// An accessor's data, every element checked to lie inside its view.
    fn accessor<'s>(&'s self, acc: &gltf::Accessor, what: &str) -> Result<AccessorData<'s>> {
        let what = format!("{what}: accessor {}", acc.index());
        if acc.sparse().is_some() {
            return Err(self.bad(format!("{what} is sparse; unsupported")));
        }
        let view = acc
            .view()
            .ok_or_else(|| self.bad(format!("{what} has no buffer view")))?;
        let bytes = self.view_bytes(&view, &what)?;
        let dims = acc.dimensions().multiplicity();
        let elem = acc.data_type().size() * dims;
        let stride = view.stride().unwrap_or(elem);
        let count = acc.count();
        if count == 0 {
            return Err(self.bad(format!("{what} has no elements")));
        }
        if stride < elem {
            return Err(self.bad(format!(
                "{what}: stride {stride} is shorter than an element ({elem} bytes)"
            )));
        }
        let end = (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(elem))
            .and_then(|x| x.checked_add(acc.offset()));
        match end {
            Some(end) if end <= bytes.len() => Ok(AccessorData {
                bytes: &bytes[acc.offset()..end],
                stride,
                count,
                component: acc.data_type(),
                dims,
                normalized: acc.normalized(),
            }),
            _ => Err(self.bad(format!(
                "{what}: {count} elements of {elem} bytes (stride {stride}, offset {}) do not fit in buffer view {} \
                 ({} bytes)",
                acc.offset(),
                view.index(),
                bytes.len()
            ))),
        }
    }

    fn read_materials(&mut self, gltf: &gltf::Gltf) -> Result<(Vec<Material>, Vec<Image>)> {
        let mut images: Vec<Image> = Vec::new();
        // glTF image index → index in `images` (None: not decodable, the factor alone is used).
        let mut decoded: Vec<Option<Option<usize>>> = vec![None; gltf.images().len()];
        let mut materials = Vec::new();
        for m in gltf.materials() {
            let what = format!("material {}", m.index().unwrap_or(0));
            let pbr = m.pbr_metallic_roughness();
            let f = pbr.base_color_factor();
            let mut factor = [f[0], f[1], f[2]].map(f64::from);
            if !factor.iter().all(|c| c.is_finite()) {
                return Err(self.bad(format!("{what}: baseColorFactor {f:?} is not finite")));
            }
            if !factor.iter().all(|c| (0.0..=1.0).contains(c)) {
                self.warnings.push(format!(
                    "{}: {what}: baseColorFactor {f:?} outside 0…1, clamped",
                    self.path.display()
                ));
                factor = factor.map(|c| c.clamp(0.0, 1.0));
            }
            let mut texture = None;
            if let Some(info) = pbr.base_color_texture() {
                let tex = info.texture();
                let img = tex.source();
                // Decoded once per image, a failure (a JPEG) included.
                let image = match decoded.get(img.index()).copied() {
                    Some(Some(known)) => known,
                    _ => {
                        let idx = match self.decode_image(&img, &what)? {
                            Some(image) => {
                                images.push(image);
                                Some(images.len() - 1)
                            }
                            None => None,
                        };
                        if let Some(s) = decoded.get_mut(img.index()) {
                            *s = Some(idx);
                        }
                        idx
                    }
                };
                if let Some(image) = image {
                    let s = tex.sampler();
                    texture = Some(TextureRef {
                        image,
                        tex_coord: info.tex_coord(),
                        wrap_s: wrap_of(s.wrap_s()),
                        wrap_t: wrap_of(s.wrap_t()),
                        filter: match s.mag_filter() {
                            Some(gltf::texture::MagFilter::Nearest) => Filter::Nearest,
                            _ => Filter::Linear,
                        },
                    });
                }
            }
            materials.push(Material {
                base_color_factor: factor,
                base_color_texture: texture,
            });
        }
        Ok((materials, images))
    }

    /// Decodes an image: `Some` for a PNG, `None` with a warning for a format without a decoder.
    fn decode_image(&mut self, img: &gltf::Image, material: &str) -> Result<Option<Image>> {
        let what = format!("{material}: image {}", img.index());
        let bytes: Vec<u8> = match img.source() {
            gltf::image::Source::View { view, .. } => self.view_bytes(&view, &what)?.to_vec(),
            gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
                Some(rest) => decode_data_uri(rest).ok_or_else(|| self.bad(format!("{what}: bad base64 data URI")))?,
                None => self.read_uri_file(uri, &what)?,
            },
        };
        if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
            let image = Image::decode_png(&bytes).map_err(|e| self.bad(format!("{what}: {e}")))?;
            self.texels += u64::from(image.width()) * u64::from(image.height());
            if self.texels > MAX_SCENE_TEXELS {
                return Err(self.bad(format!(
                    "{what}: the scene's images hold more than {MAX_SCENE_TEXELS} texels together"
                )));
            }
            return Ok(Some(image));
        }
        let kind = if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
            "a JPEG image"
        } else {
            "not a PNG image"
        };
        self.warnings.push(format!(
            "{}: {what} is {kind}, which lumiview cannot decode (PNG only); its base colour factor alone is used",
            self.path.display()
        ));
        Ok(None)
    }

    /// Appends a primitive's triangles (world space) with their material and UVs.
    fn read_primitive(
        &self,
        prim: &gltf::Primitive,
        what: &str,
        world: DMat4,
        material: u32,
        tex_coord: Option<u32>,
        parts: &mut SceneParts,
    ) -> Result<()> {
        use gltf::mesh::Mode;
        let mode = prim.mode();
        let pos_acc = prim
            .get(&gltf::Semantic::Positions)
            .ok_or_else(|| self.bad(format!("{what} has no POSITION")))?;
        let pos = self.accessor(&pos_acc, what)?;
        if pos.component != DataType::F32 || pos.dims != 3 || pos_acc.dimensions() != Dimensions::Vec3 {
            return Err(self.bad(format!(
                "{what}: POSITION is {:?} {:?}; only FLOAT VEC3 is supported",
                pos_acc.data_type(),
                pos_acc.dimensions()
            )));
        }
        if pos.count > 3 * MAX_TRIANGLES {
            return Err(self.bad(format!(
                "{what}: {} vertices; at most {} are supported",
                pos.count,
                3 * MAX_TRIANGLES
            )));
        }
        // A mesh is read again for every node that uses it: the reads of all of them are bounded
        // (100,000 nodes of one 24 M-vertex mesh would otherwise take hours).
        let read = self.vertices_read.get() + pos.count as u64;
        if read > MAX_VERTICES_READ {
            return Err(self.bad(format!(
                "{what}: the scene's nodes read more than {MAX_VERTICES_READ} vertices together"
            )));
        }
        self.vertices_read.set(read);
        let mut positions: Vec<DVec3> =
            crate::files::try_vec(pos.count, "positions").map_err(|e| self.bad(format!("{what}: {e}")))?;
        for i in 0..pos.count {
            let p = DVec3::new(pos.component(i, 0), pos.component(i, 1), pos.component(i, 2));
            if !p.is_finite() {
                return Err(self.bad(format!("{what}: position {i} {p} is not finite")));
            }
            positions.push(world.transform_point3(p));
        }
        let uvs: Option<Vec<[f32; 2]>> = match tex_coord {
            None => None,
            Some(set) => {
                let acc = prim.get(&gltf::Semantic::TexCoords(set)).ok_or_else(|| {
                    self.bad(format!(
                        "{what}: its material's texture reads TEXCOORD_{set}, which the primitive lacks"
                    ))
                })?;
                let uv = self.accessor(&acc, what)?;
                let ok = uv.dims == 2
                    && (uv.component == DataType::F32
                        || (uv.normalized && matches!(uv.component, DataType::U8 | DataType::U16)));
                if !ok || uv.count != pos.count {
                    return Err(self.bad(format!(
                        "{what}: TEXCOORD_{set} is {} × {:?} {:?}; expected {} FLOAT (or normalized unsigned) VEC2",
                        uv.count,
                        acc.data_type(),
                        acc.dimensions(),
                        pos.count
                    )));
                }
                Some(
                    (0..uv.count)
                        .map(|i| [uv.component(i, 0) as f32, uv.component(i, 1) as f32])
                        .collect(),
                )
            }
        };
        // The triangles this primitive makes, checked against the limit before anything of its
        // size is allocated (a buffer of zero indices passes the range check).
        let count_triangles = |n: usize| match mode {
            Mode::TriangleStrip | Mode::TriangleFan => n.saturating_sub(2),
            _ => n / 3,
        };
        let index_count = match prim.indices() {
            Some(ref acc) => acc.count(),
            None => positions.len(),
        };
        if count_triangles(index_count) > MAX_TRIANGLES.saturating_sub(parts.triangles.len()) {
            return Err(self.bad(format!("{what}: more than {MAX_TRIANGLES} triangles; unsupported")));
        }
        let indices: Vec<u32> = match prim.indices() {
            Some(acc) => {
                let ix = self.accessor(&acc, what)?;
                if ix.dims != 1 || !matches!(ix.component, DataType::U8 | DataType::U16 | DataType::U32) {
                    return Err(self.bad(format!(
                        "{what}: indices are {:?} {:?}; expected unsigned SCALAR",
                        acc.data_type(),
                        acc.dimensions()
                    )));
                }
                let mut v = crate::files::try_vec(ix.count, "indices").map_err(|e| self.bad(format!("{what}: {e}")))?;
                for i in 0..ix.count {
                    let k = ix.index(i);
                    if k as usize >= positions.len() {
                        return Err(self.bad(format!(
                            "{what}: index {i} is {k}, beyond its {} vertices",
                            positions.len()
                        )));
                    }
                    v.push(k);
                }
                v
            }
            None => (0..positions.len() as u32).collect(),
        };
        let triples: Vec<[u32; 3]> = match mode {
            Mode::TriangleStrip => (2..indices.len())
                .map(|i| {
                    if i % 2 == 0 {
                        [indices[i - 2], indices[i - 1], indices[i]]
                    } else {
                        [indices[i - 1], indices[i - 2], indices[i]]
                    }
                })
                .collect(),
            Mode::TriangleFan => (2..indices.len())
                .map(|i| [indices[0], indices[i - 1], indices[i]])
                .collect(),
            _ => indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        };
        if parts.triangles.len() + triples.len() > MAX_TRIANGLES {
            return Err(self.bad(format!("more than {MAX_TRIANGLES} triangles; unsupported")));
        }
        let mirrored = world.determinant() < 0.0;
        for t in triples {
            let t = if mirrored { [t[0], t[2], t[1]] } else { t };
            parts.triangles.push(t.map(|k| positions[k as usize]));
            parts.material_of.push(material);
            parts.uvs.push(match &uvs {
                Some(uv) => t.map(|k| uv[k as usize]),
                None => [[0.0; 2]; 3],
            });
        }
        Ok(())
    }
}

/// Whether a primitive mode draws triangles.
fn is_surface(mode: gltf::mesh::Mode) -> bool {
    use gltf::mesh::Mode;
    matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan)
}

/// Whether a URI starts with a scheme (`http:`, `file:`; RFC 3986: a letter, then letters, digits,
/// `+`, `-` or `.`, then `:`).
fn has_uri_scheme(uri: &str) -> bool {
    let Some((scheme, _)) = uri.split_once(':') else {
        return false;
    };
    let mut chars = scheme.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
}

fn wrap_of(w: gltf::texture::WrappingMode) -> Wrap {
    match w {
        gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
    }
}

/// The payload of a `data:` URI (after `data:`) when it is base64 (`MIME;base64,DATA`).
fn decode_data_uri(rest: &str) -> Option<Vec<u8>> {
    let (_, b64) = rest.split_once(";base64,")?;
    decode_base64(b64)
}

/// Standard or URL-safe base64, padding optional, whitespace ignored.
fn decode_base64(s: &str) -> Option<Vec<u8>> {
    let val = |c: u8| -> Option<u32> {
        Some(u32::from(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        }))
    };
    let digits: Vec<u8> = s.bytes().filter(|c| !c.is_ascii_whitespace() && *c != b'=').collect();
    let mut out = Vec::with_capacity(digits.len() / 4 * 3 + 3);
    for chunk in digits.chunks(4) {
        if chunk.len() < 2 {
            return None;
        }
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            acc |= val(c)? << (18 - 6 * k);
        }
        let bytes = acc.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Some(out)
}

/// `%XX` escapes of a URI decoded (UTF-8); `None` for a malformed escape.
fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_and_percent_escapes_decode() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("AAEC").unwrap(), vec![0, 1, 2]);
        assert!(decode_base64("a$==").is_none());
        assert!(decode_base64("AAECA").is_none());
        assert_eq!(
            decode_data_uri("application/octet-stream;base64,AAEC").unwrap(),
            vec![0, 1, 2]
        );
        assert_eq!(percent_decode("my%20scene.bin").unwrap(), "my scene.bin");
        assert!(percent_decode("bad%2").is_none());
        assert!(percent_decode("bad%zz").is_none());
        assert!(has_uri_scheme("http://x/a.bin") && has_uri_scheme("file:a.bin"));
        assert!(!has_uri_scheme("a.bin") && !has_uri_scheme("dir/a:b.bin") && !has_uri_scheme(":a"));
    }

    #[test]
    fn glb_headers_are_checked_before_gltf_reads_them() {
        assert!(crate::draw::glb::check_header(b"{\"asset\":{}}").is_ok(), "JSON passes");
        assert!(crate::draw::glb::check_header(b"glTF\x02\0\0\0")
            .unwrap_err()
            .contains("truncated"));
        let mut h = b"glTF\x02\0\0\0\x05\0\0\0".to_vec();
        h.resize(40, 0);
        assert!(crate::draw::glb::check_header(&h).unwrap_err().contains("says 5 bytes"));
        h[8] = 200;
        assert!(crate::draw::glb::check_header(&h)
            .unwrap_err()
            .contains("says 200 bytes"));
        h[4] = 1;
        assert!(crate::draw::glb::check_header(&h).unwrap_err().contains("version 1"));
    }
}

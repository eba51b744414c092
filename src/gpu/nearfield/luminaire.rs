//! A scanned luminaire on the GPU ([`NearfieldLuminaire`]) and making the chunks a view can read
//! resident.

use std::sync::{Arc, Mutex};

use glam::{DVec3, Mat4, Vec4};

use super::records::PoolLayout;
use crate::gpu::context::GpuContext;
use crate::gpu::residency::{ChunkLayout, Residency, Uploads, CHUNK_BYTES, EMPTY};
use crate::gpu::{Arg, GpuError};
use crate::nearfield::farfield::{FarField, FarFieldOptions};
use crate::nearfield::pack::Pack;
use crate::nearfield::select::lit_bound::{LitDirections, PolygonKind, PolygonVertex, EMPTY_TRIANGLE};
use crate::nearfield::select::view::view_cells;
use crate::nearfield::select::{Selection, SelectionMode};
use crate::photometry::Photometry;

/// A scanned luminaire on the GPU; instances share it.
pub struct NearfieldLuminaire {
    /// The pack it reads from.
    pub pack: Arc<Pack>,
    /// The selection tables.
    pub selection: Arc<Selection>,
    /// Capture centre (m, luminaire frame) and radius (m).
    pub sphere: (DVec3, f64),
    /// Radius (m) of the content ball around the capture centre.
    pub content_radius_m: f64,
    /// Whether the whole pack is resident (no streaming).
    pub fully_resident: bool,
    /// Whether pack chunk c is pool chunk c (fully resident, every chunk in use): the shader skips
    /// the chunk map.
    pub(super) identity_map: bool,
    pub(super) chunks: ChunkLayout,
    pub(super) residency: Mutex<Residency>,
    pub(super) chunk_map: wgpu::Buffer,
    pub(super) misses: wgpu::Buffer,
    pub(super) pages: Vec<wgpu::Buffer>,
    pub(super) chunks_per_page: u32,
    pub(super) pool_layout: PoolLayout,
    /// The directions each camera's tile box covers, for the bounding polygon (bounding mode).
    pub(super) lit: LitDirections,
    pub(super) bounding_polygon: bool,
    /// Whether the proxy has a hierarchy for the visibility test (a planar one needs none).
    pub(super) has_bvh: bool,
    pub(super) bind: wgpu::BindGroup,
    pub(super) bounds: (wgpu::Buffer, u32),
    pub(super) proxy: Option<(wgpu::Buffer, u32)>,
    pub(super) gpu_bytes: u64,
    pub(super) budget_bytes: u64,
    /// Its far-field photometry, estimated from the pack when a scene first needs it.
    pub(super) far_field: std::sync::OnceLock<Result<Arc<Photometry>, String>>,
}

impl std::fmt::Debug for NearfieldLuminaire {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NearfieldLuminaire")
            .field("pack", &self.pack)
            .field("content_radius_m", &self.content_radius_m)
            .field("fully_resident", &self.fully_resident)
            .field("gpu_bytes", &self.gpu_bytes)
            .finish_non_exhaustive()
    }
}

/// Residency figures of a luminaire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ResidencyReport {
    /// Bytes of every GPU buffer the luminaire holds (never above the budget).
    pub gpu_bytes: u64,
    /// The budget it was created with.
    pub budget_bytes: u64,
    /// Chunks the pool can hold.
    pub capacity_chunks: u32,
    /// Chunks resident now.
    pub resident_chunks: u32,
    /// Chunks the whole pack has.
    pub total_chunks: u32,
    /// Chunks uploaded so far.
    pub uploads: u64,
    /// Chunks evicted so far.
    pub evictions: u64,
}

impl NearfieldLuminaire {
    /// Residency figures.
    pub fn residency(&self) -> ResidencyReport {
        let r = self.residency.lock().unwrap_or_else(|p| p.into_inner());
        ResidencyReport {
            gpu_bytes: self.gpu_bytes,
            budget_bytes: self.budget_bytes,
            capacity_chunks: r.capacity(),
            resident_chunks: r.resident() as u32,
            total_chunks: self.chunks.all_needed().len() as u32,
            uploads: r.uploads,
            evictions: r.evictions,
        }
    }

    /// The scan's far-field intensity as photometry ([`FarField::estimate`] over the pack's
    /// images, default options), estimated on the first call and kept (an error too): what lights
    /// a scene. Its warnings (sparse coverage, no light at all) go to the context's log.
    ///
    /// Errors: the pack's images cannot be read (a pack that became unreadable or corrupt;
    /// `luminaire`, naming the pack).
    pub fn far_field(&self, ctx: &GpuContext) -> Result<Arc<Photometry>, GpuError> {
        self.far_field
            .get_or_init(|| {
                let pack = self.pack.as_ref();
                let name = pack.path().display().to_string();
                let ff = FarField::estimate(pack.rayset(), pack, &FarFieldOptions::default(), &|_| {})
                    .map_err(|e| format!("the far field of {name}: {e}"))?;
                for w in &ff.warnings {
                    ctx.log(crate::gpu::context::LogLevel::Warning, w);
                }
                ff.photometry(&name)
                    .map(Arc::new)
                    .map_err(|e| format!("the far field of {name}: {e}"))
            })
            .clone()
            .map_err(|e| GpuError::invalid(Arg::Luminaire, e))
    }

    /// Sets the far field [`NearfieldLuminaire::far_field`] returns (one estimated already).
    ///
    /// Errors: it is set or estimated already.
    pub fn set_far_field(&self, p: Arc<Photometry>) -> Result<(), GpuError> {
        self.far_field
            .set(Ok(p))
            .map_err(|_| GpuError::invalid(Arg::Luminaire, "its far field is set or estimated already"))
    }

    /// Whether it has a proxy mesh.
    pub fn has_proxy(&self) -> bool {
        self.proxy.is_some()
    }

    /// Reads (and resets) the shader's count of reads of non-resident chunks. Waits for the GPU.
    pub fn take_misses(&self, ctx: &GpuContext) -> Result<u32, GpuError> {
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("near-field misses read-back"),
            size: 4,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&self.misses, 0, &staging, 0, 4);
        enc.clear_buffer(&self.misses, 0, None);
        ctx.queue.submit([enc.finish()]);
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        ctx.wait_idle()?;
        let v = {
            let data = slice
                .get_mapped_range()
                .map_err(|e| GpuError::DeviceLost(format!("reading the near-field miss counter: {e}")))?;
            u32::from_le_bytes([data[0], data[1], data[2], data[3]])
        };
        staging.unmap();
        Ok(v)
    }

    /// Cameras any pixel of a view from `eye` (luminaire frame: w = 1 a point, w = 0 the direction
    /// towards an orthographic eye) can select in `mode`: those listed in the selection cells that the
    /// view's lines through the content ball reach on the capture sphere (conservative). With
    /// `clip_from_local`, only the lines inside the view's frustum count: a close-up needs the
    /// cameras of the directions it shows, not of all the ball.
    pub fn cameras_for_view(&self, eye: Vec4, clip_from_local: Option<Mat4>, mode: SelectionMode) -> Vec<u32> {
        let cells = view_cells(
            &self.selection,
            self.sphere,
            self.content_radius_m,
            eye,
            clip_from_local,
        );
        self.selection.cameras_of_cells(mode, cells.into_iter())
    }

    /// Whether a view from `eye` (as in [`Self::cameras_for_view`]) without the proxy may draw the
    /// bounding polygon: it is enabled, and the eye is a point outside the content ball.
    pub(super) fn polygon_applies(&self, eye: Vec4) -> bool {
        self.bounding_polygon
            && eye.w > 0.5
            && (eye.truncate().as_dvec3() - self.sphere.0).length() > 1.01 * self.content_radius_m
    }

    /// What the pass draws for an instance in `mode` without its proxy, seen from `eye` (luminaire
    /// frame, as in [`Self::cameras_for_view`]) through `clip_from_local` into a `viewport` of pixels:
    /// the bounding polygons ([`crate::nearfield::select::lit_bound`]) as a triangle list, and which kind they are;
    /// an empty list when no pixel can be lit; `None` where the pass draws the content ball's box.
    pub fn bounding_polygon(
        &self,
        eye: Vec4,
        clip_from_local: Mat4,
        mode: SelectionMode,
        viewport: (u32, u32),
    ) -> Option<(Vec<PolygonVertex>, PolygonKind)> {
        let applies = self.polygon_applies(eye);
        applies
            .then(|| self.view_geometry(eye, clip_from_local, mode, viewport, applies).1)
            .flatten()
    }

    /// The cameras a view can select, and (`polygon`: where it applies) its bounding polygons.
    #[allow(clippy::type_complexity)]
    pub(super) fn view_geometry(
        &self,
        eye: Vec4,
        clip_from_local: Mat4,
        mode: SelectionMode,
        viewport: (u32, u32),
        polygon: bool,
    ) -> (Vec<u32>, Option<(Vec<PolygonVertex>, PolygonKind)>) {
        // Residency needs the cameras from the cell grid; the polygons the faster superset.
        let resident = if self.fully_resident {
            Vec::new()
        } else {
            self.cameras_for_view(eye, Some(clip_from_local), mode)
        };
        if !polygon {
            return (resident, None);
        }
        let Some((cams, tris)) = self
            .lit
            .selectable(&self.selection, eye.truncate(), self.content_radius_m, mode)
        else {
            return (resident, None);
        };
        // Blending over triangles (continuous): the triangle raster; otherwise, or where it does not
        // apply, the hull.
        if mode.blends_triangles() {
            let raster = self.lit.continuous_raster(
                &self.selection,
                &tris,
                clip_from_local,
                eye.truncate(),
                self.content_radius_m,
                viewport,
            );
            if let Some(r) = raster {
                return (resident, Some((r, PolygonKind::Triangles)));
            }
        }
        if mode == SelectionMode::Nearest {
            let raster =
                self.lit
                    .nearest_raster(&cams, clip_from_local, eye.truncate(), self.content_radius_m, viewport);
            if let Some(r) = raster {
                return (resident, Some((r, PolygonKind::Cells)));
            }
        }
        let hull = self.lit.bound(&cams, mode, clip_from_local, eye.truncate()).map(|p| {
            let v = p.into_iter().map(|pos| PolygonVertex {
                pos,
                tri: EMPTY_TRIANGLE,
            });
            (v.collect(), PolygonKind::Hull)
        });
        (resident, hull)
    }

    pub(super) fn make_resident(&self, ctx: &GpuContext, cameras: &[u32]) -> Result<(), GpuError> {
        if self.fully_resident {
            return Ok(());
        }
        let needed = self.chunks.chunks_of(cameras.iter().copied());
        let mut r = self.residency.lock().unwrap_or_else(|p| p.into_inner());
        let uploads = r
            .make_resident(&needed)
            .map_err(|m| GpuError::invalid(Arg::BudgetBytes, m))?;
        if uploads.is_empty() {
            return Ok(());
        }
        self.write_chunks(ctx, uploads, &r.map)
    }

    /// Writes the uploaded chunks into their pool pages and the new chunk map.
    fn write_chunks(&self, ctx: &GpuContext, uploads: Uploads, map: &[u32]) -> Result<(), GpuError> {
        for (g, c) in uploads {
            let bytes = self.chunks.chunk_bytes(&self.pack, c)?;
            let page = (g / self.chunks_per_page) as usize;
            let off = u64::from(g % self.chunks_per_page) * CHUNK_BYTES;
            if !bytes.is_empty() {
                ctx.queue.write_buffer(&self.pages[page], off, &bytes);
            }
        }
        ctx.queue.write_buffer(&self.chunk_map, 0, bytemuck::cast_slice(map));
        Ok(())
    }

    pub(super) fn make_resident_chunks(&self, ctx: &GpuContext, chunks: &[u32]) -> Result<(), GpuError> {
        let mut r = self.residency.lock().unwrap_or_else(|p| p.into_inner());
        // Keep what earlier batches uploaded: stamp them as needed too.
        let mut needed: Vec<u32> = r
            .map
            .iter()
            .enumerate()
            .filter(|(_, g)| **g != EMPTY)
            .map(|(c, _)| c as u32)
            .collect();
        needed.extend_from_slice(chunks);
        needed.sort_unstable();
        needed.dedup();
        let uploads = r
            .make_resident(&needed)
            .map_err(|m| GpuError::invalid(Arg::BudgetBytes, m))?;
        self.write_chunks(ctx, uploads, &r.map)
    }
}

//! Per-draw records in one buffer, each at a 256-byte slot bound with a dynamic offset: the draw
//! uniforms of the far-field pass and the draw records of the near-field pass.

use super::context::GpuContext;

/// Bytes between two draws' records (the dynamic-offset alignment every device accepts).
pub const SLOT: u64 = 256;

/// A growable buffer of per-draw records and its bind group (binding 0, one record wide).
#[derive(Debug)]
pub struct DrawSlots {
    label: &'static str,
    usage: wgpu::BufferUsages,
    current: Option<(wgpu::Buffer, u64, wgpu::BindGroup)>,
}

impl DrawSlots {
    /// An empty set; `usage` is `UNIFORM` or `STORAGE` (COPY_DST is added).
    pub fn new(label: &'static str, usage: wgpu::BufferUsages) -> Self {
        DrawSlots {
            label,
            usage,
            current: None,
        }
    }

    /// Writes `records` at slots 0, 1, … (growing the buffer to a power of two when needed) and returns
    /// the bind group to use with dynamic offset `k · SLOT` for record k.
    pub fn write<T: bytemuck::Pod>(
        &mut self,
        ctx: &GpuContext,
        layout: &wgpu::BindGroupLayout,
        records: &[T],
    ) -> &wgpu::BindGroup {
        let needed = (records.len().max(1) as u64) * SLOT;
        let current = match self.current.take() {
            Some(c) if c.1 >= needed => c,
            _ => {
                let cap = needed.next_power_of_two();
                let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(self.label),
                    size: cap,
                    usage: self.usage | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(self.label),
                    layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &buf,
                            offset: 0,
                            size: wgpu::BufferSize::new(std::mem::size_of::<T>() as u64),
                        }),
                    }],
                });
                (buf, cap, bind)
            }
        };
        let (buf, _, bind) = self.current.insert(current);
        let mut bytes = vec![0u8; records.len() * SLOT as usize];
        for (k, r) in records.iter().enumerate() {
            let b = bytemuck::bytes_of(r);
            bytes[k * SLOT as usize..k * SLOT as usize + b.len()].copy_from_slice(b);
        }
        if !bytes.is_empty() {
            ctx.queue.write_buffer(buf, 0, &bytes);
        }
        bind
    }

    /// The bind group of the last [`DrawSlots::write`], if any.
    pub fn bind_group(&self) -> Option<&wgpu::BindGroup> {
        self.current.as_ref().map(|c| &c.2)
    }
}

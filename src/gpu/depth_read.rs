//! Depth read-back where the backend cannot copy depth into buffers.
//!
//! WebGPU lets a depth texture be copied into a buffer only where the downlevel flag
//! `DEPTH_TEXTURE_AND_BUFFER_COPIES` is present: Vulkan has it, GL (EGL + llvmpipe, GLES) does not,
//! so a `copy_texture_to_buffer` of depth fails there on every frame. [`DepthReader`] instead
//! binds the depth texture (which needs `TEXTURE_BINDING` usage) as an unfilterable-float texture
//! to a compute pass (`shaders/depth_copy.wgsl`) that writes one f32 per texel into a storage
//! buffer, row-major and unpadded, which is then copied into a mappable buffer. The raw values are
//! bit for bit those of the texture (a `textureLoad`, no filtering, no conversion).
//!
//! [`GpuContext::read_depth`](super::GpuContext::read_depth) uses it only where the flag is
//! missing: measured on lavapipe at 1280 × 1024, the pass costs 5.9 ms against 0.4 ms for the copy
//! (12 ms on llvmpipe's GL), so Vulkan keeps the copy and its read-back time. The unit tests run
//! the pass on every backend.
//!
//! Images taller than one storage binding allows (`max_storage_buffer_binding_size`, 128 MiB on
//! lavapipe: 8192 rows of 4096 texels) are copied in bands of rows, each bound at an offset that
//! is a multiple of 256 bytes (bands are multiples of 64 rows).

use super::readback::ReadbackTexture;
use super::shader::{float_texture_entry, storage_entry, uniform_entry};
use crate::error::Result;
use wgpu::util::DeviceExt;

/// Rows of a band are a multiple of this, so band offsets (`rows * width * 4` bytes) are
/// multiples of 256 bytes, the largest storage-buffer offset alignment wgpu allows.
const BAND_ROWS: u32 = 64;

/// The compute pipeline that copies depth texels into a buffer.
pub struct DepthReader {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

/// A depth texture's texels on their way into host memory, by copy or through the shader.
pub enum DepthReadback {
    /// `copy_texture_to_buffer` (rows padded to 256 bytes).
    Copy(ReadbackTexture),
    /// Through [`DepthReader`] (one f32 per texel, row-major, no padding).
    Shader { buffer: wgpu::Buffer, texels: usize },
}

impl DepthReader {
    pub fn new(d: &wgpu::Device) -> Self {
        let cs = wgpu::ShaderStages::COMPUTE;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("depth_copy"),
            entries: &[float_texture_entry(0, cs), storage_entry(1, false, cs), uniform_entry(2, cs)],
        });
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("depth_copy.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/depth_copy.wgsl").into()),
        });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("depth_copy"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("depth_copy"),
            layout: Some(&pl),
            module: &module,
            entry_point: Some("copy_depth"),
            compilation_options: Default::default(),
            cache: None,
        });
        Self { layout, pipeline }
    }

    /// Records the copy of the depth texture behind `view` (`width` × `height`, a Depth32Float
    /// texture with `TEXTURE_BINDING` usage) into a new mappable buffer; `max_binding` is the
    /// device's `max_storage_buffer_binding_size`.
    pub fn record(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        (width, height): (u32, u32),
        max_binding: u64,
    ) -> DepthReadback {
        let row_bytes = 4 * width as u64;
        let size = row_bytes * height as u64;
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let texels = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("depth_texels"),
            size,
            usage,
            mapped_at_creation: false,
        });
        let rows_per_band = band_rows(width, height, max_binding);
        let mut y0 = 0;
        while y0 < height {
            let rows = rows_per_band.min(height - y0);
            let band = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("depth_band"),
                contents: bytemuck::cast_slice(&[y0, rows, 0, 0]),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("depth_copy"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(view) },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &texels,
                            offset: y0 as u64 * row_bytes,
                            size: wgpu::BufferSize::new(rows as u64 * row_bytes),
                        }),
                    },
                    wgpu::BindGroupEntry { binding: 2, resource: band.as_entire_binding() },
                ],
            });
            let mut pass = enc
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("depth_copy"), timestamp_writes: None });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bg, &[]);
            pass.dispatch_workgroups(width.div_ceil(16), rows.div_ceil(16), 1);
            drop(pass);
            y0 += rows;
        }
        let buffer = super::readback::copy_buffer(d, enc, &texels, size);
        DepthReadback::Shader { buffer, texels: (width * height) as usize }
    }
}

/// Rows per band: as many as one storage binding of `max_binding` bytes holds, a multiple of
/// [`BAND_ROWS`] (at least one band of `BAND_ROWS` rows: 64 rows of the widest texture wgpu
/// allows, 16384 texels, are 4 MiB, under every device's binding limit).
pub(crate) fn band_rows(width: u32, height: u32, max_binding: u64) -> u32 {
    let fit = (max_binding / (4 * width as u64)).min(height as u64) as u32;
    if fit >= height {
        height
    } else {
        (fit / BAND_ROWS * BAND_ROWS).max(BAND_ROWS)
    }
}

impl DepthReadback {
    /// The buffer to map.
    pub fn buffer(&self) -> &wgpu::Buffer {
        match self {
            Self::Copy(t) => &t.buffer,
            Self::Shader { buffer, .. } => buffer,
        }
    }

    /// The raw depth values (row 0 = top), after the buffer was mapped.
    pub fn read(&self) -> Result<Vec<f32>> {
        match self {
            Self::Copy(t) => Ok(bytemuck::cast_slice(&t.read_rows()?).to_vec()),
            Self::Shader { buffer, texels } => {
                let v: Vec<f32> = super::readback::read_mapped(buffer)?;
                debug_assert_eq!(v.len(), *texels);
                Ok(v)
            }
        }
    }
}

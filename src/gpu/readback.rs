//! Copies from the GPU into host memory: textures with padded rows, and buffers.

use crate::error::{Error, Result};

/// A texture copied into a mappable buffer with 256-byte aligned rows.
pub struct ReadbackTexture {
    pub buffer: wgpu::Buffer,
    row_bytes: u32,
    padded: u32,
    height: u32,
}

impl ReadbackTexture {
    /// Records the copy of `tex` (`w` × `h` texels of `bpp` bytes, one aspect) into `enc`.
    pub fn new(
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        tex: &wgpu::Texture,
        w: u32,
        h: u32,
        bpp: u32,
        aspect: wgpu::TextureAspect,
    ) -> Self {
        let row_bytes = w * bpp;
        let padded = row_bytes.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback_texture"),
            size: padded as u64 * h as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { texture: tex, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(padded), rows_per_image: Some(h) },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        Self { buffer, row_bytes, padded, height: h }
    }

    /// The rows without padding, after the buffer was mapped.
    pub fn read_rows(&self) -> Result<Vec<u8>> {
        let data = self.buffer.slice(..).get_mapped_range().map_err(map_err)?;
        let mut out = Vec::with_capacity((self.row_bytes * self.height) as usize);
        for r in 0..self.height as usize {
            let s = r * self.padded as usize;
            out.extend_from_slice(&data[s..s + self.row_bytes as usize]);
        }
        Ok(out)
    }
}

/// Records a copy of the first `size` bytes of `src` into a new mappable buffer.
pub fn copy_buffer(d: &wgpu::Device, enc: &mut wgpu::CommandEncoder, src: &wgpu::Buffer, size: u64) -> wgpu::Buffer {
    let b = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    enc.copy_buffer_to_buffer(src, 0, &b, 0, size);
    b
}

/// Starts mapping every buffer for reading (complete after the next `GpuContext::wait`).
pub fn map_all<'a>(buffers: impl IntoIterator<Item = &'a wgpu::Buffer>) {
    for b in buffers {
        b.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    }
}

/// The contents of a mapped buffer as `T`s.
pub fn read_mapped<T: bytemuck::Pod>(b: &wgpu::Buffer) -> Result<Vec<T>> {
    Ok(bytemuck::cast_slice(&b.slice(..).get_mapped_range().map_err(map_err)?).to_vec())
}

pub fn map_err(e: impl std::fmt::Display) -> Error {
    Error::Device(format!("reading back from the GPU failed: {e}"))
}

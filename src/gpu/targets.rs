//! Render targets: colour, tile id and depth textures of one size.

/// Colour of the final image.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Tile index + 1 of the front-most surface per pixel (0 = nothing).
pub const ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// Reverse-Z depth (1 = near, 0 = far or empty).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Background colour of the image (opaque black).
#[cfg(test)]
pub const BACKGROUND: [u8; 4] = [0, 0, 0, 255];

/// Textures of one size: an optional colour target, the tile-id target and depth.
pub struct Targets {
    pub width: u32,
    pub height: u32,
    pub color_tex: Option<wgpu::Texture>,
    pub color: Option<wgpu::TextureView>,
    pub id: wgpu::TextureView,
    pub depth_tex: wgpu::Texture,
    pub depth: wgpu::TextureView,
}

/// A 2-D texture of `size` with one mip level and one sample.
pub fn texture(
    d: &wgpu::Device,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    d.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

impl Targets {
    /// `with_color`: the final image's targets; without, an id + depth prepass.
    pub fn new(d: &wgpu::Device, width: u32, height: u32, with_color: bool) -> Self {
        let ra = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let color_tex =
            with_color.then(|| texture(d, "color", width, height, COLOR_FORMAT, ra | wgpu::TextureUsages::COPY_SRC));
        let id = texture(d, "id", width, height, ID_FORMAT, ra | wgpu::TextureUsages::TEXTURE_BINDING);
        // Copied for read-back, or read through a shader where it cannot be (`gpu::depth_read`).
        let depth_usage = ra | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING;
        let depth_tex = texture(d, "depth", width, height, DEPTH_FORMAT, depth_usage);
        Self {
            width,
            height,
            color: color_tex.as_ref().map(|t| t.create_view(&Default::default())),
            color_tex,
            id: id.create_view(&Default::default()),
            depth: depth_tex.create_view(&Default::default()),
            depth_tex,
        }
    }

    /// Keeps `slot` holding targets of `width` × `height` (re-created when the size changes).
    pub fn ensure<'a>(slot: &'a mut Option<Targets>, d: &wgpu::Device, width: u32, height: u32) -> &'a Targets {
        if slot.as_ref().is_none_or(|t| (t.width, t.height) != (width, height)) {
            *slot = Some(Targets::new(d, width, height, false));
        }
        slot.as_ref().unwrap()
    }
}

//! The wgpu renderer.
//!
//! One frame is one submission. For `Culling::ThreePass`:
//! 1. depth prepass of every visible tile's coarse proxy (at `prepass_scale` × the image size),
//!    writing depth and the tile id;
//! 2. compute histogram of the id buffer: the exact number of pixels where each tile's coarse proxy
//!    is the front-most surface (no occlusion queries: those are boolean on several backends);
//! 3. compute pass writing one indirect draw per tile (instance_count 0 below the threshold), then
//!    the lit fine pass draws them all with one `multi_draw_indexed_indirect`.
//!
//! Other strategies (none, oracle, CPU culling) hand the final pass a tile mask built on the CPU.
//! The final pass always writes the tile id as well, so the visible pixels of each fine tile can be
//! counted from the final image with the same histogram.

mod context;

pub use context::{GpuContext, INSTALL_HINT};

use crate::camera::{Camera, FrameCamera};
use crate::cull::Culling;
use crate::error::{ensure, Error, Result};
use crate::scene::Scene;
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Mat4};
use rayon::prelude::*;
use std::time::Instant;
use wgpu::util::DeviceExt;

const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Background colour of the image (opaque black).
pub const BACKGROUND: [u8; 4] = [0, 0, 0, 255];

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug, Default, PartialEq)]
pub struct DrawArgs {
    pub index_count: u32,
    pub instance_count: u32,
    pub first_index: u32,
    pub base_vertex: i32,
    pub first_instance: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    light_dir: [f32; 4],
    z_scale: f32,
    _pad: [f32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuObject {
    offset: [f32; 4],
    color: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CullParams {
    n_tiles: u32,
    threshold: f32,
    _pad: [u32; 2],
}

/// How to render one frame.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub culling: Culling,
    /// Tiles with at most this many visible pixels (full-image units) are not drawn (three_pass).
    pub pixel_threshold: f64,
    /// Prepass resolution relative to the image, in (0, 1] (three_pass).
    pub prepass_scale: f64,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { culling: Culling::None, pixel_threshold: 10.0, prepass_scale: 1.0 }
    }
}

/// Timings and counts of one frame.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub triangles_fine_total: u64,
    pub triangles_drawn: u64,
    pub triangles_prepass: u64,
    pub tiles_total: u32,
    pub tiles_drawn: u32,
    /// Per-pass GPU times (timestamps where the adapter has them, else 0) in milliseconds.
    pub prepass_ms: f64,
    pub count_ms: f64,
    pub draw_ms: f64,
    /// CPU culling time (strategies that cull on the CPU).
    pub cull_ms: f64,
    /// Wall time from the call to the GPU finishing the frame (no read-back), milliseconds.
    pub total_ms: f64,
    /// Wall time to copy the image, depth and counts back and convert them.
    pub readback_ms: f64,
    pub gpu_timestamps: bool,
    /// Horizon culling: quadtree nodes visited and culled (all height fields together).
    pub nodes_visited: u32,
    pub nodes_culled: u32,
}

/// The result of one frame, as plain host arrays.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    pub width: u32,
    pub height: u32,
    /// RGBA8, row-major, row 0 = top.
    pub image: Vec<u8>,
    /// Distance along the view axis (render-space units), +inf where empty.
    pub depth: Vec<f32>,
    /// Visible pixels per tile: pass-2 counts scaled to full-image pixels for three_pass; counts
    /// in the unculled image for oracle; in the final image for none and horizon.
    pub tile_pixels: Vec<u32>,
    pub tile_drawn: Vec<bool>,
    pub stats: RenderStats,
    pub near: f64,
    pub far: f64,
    /// Horizon culling: the final horizon of the first height field, one value per image column
    /// (pixel rows from the bottom that are known hidden; -inf where none).
    pub horizon: Option<Vec<f32>>,
}

/// GPU copy of a scene's geometry.
pub(crate) struct SceneGpu {
    key: (u64, u64),
    vertices: Option<wgpu::Buffer>,
    indices: Option<wgpu::Buffer>,
    /// Object index (position in `scene.objects()`) of every tile.
    tile_object: wgpu::Buffer,
    tile_object_cpu: Vec<u32>,
    fine: Vec<DrawArgs>,
    coarse: Vec<DrawArgs>,
    /// Origin-relative tile bounds (no offset, no exaggeration), for front-to-back ordering.
    bbox: Vec<(DVec3, DVec3)>,
    bytes: u64,
}

pub(crate) struct Targets {
    width: u32,
    height: u32,
    color: Option<wgpu::TextureView>,
    color_tex: Option<wgpu::Texture>,
    id: wgpu::TextureView,
    depth: wgpu::TextureView,
    depth_tex: wgpu::Texture,
}

pub struct Renderer {
    pub(crate) ctx: GpuContext,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) scene_layout: wgpu::BindGroupLayout,
    pub(crate) hist_layout: wgpu::BindGroupLayout,
    pub(crate) args_layout: wgpu::BindGroupLayout,
    pub(crate) main_pipeline: wgpu::RenderPipeline,
    pub(crate) prepass_pipeline: wgpu::RenderPipeline,
    pub(crate) hist_pipeline: wgpu::ComputePipeline,
    pub(crate) args_pipeline: wgpu::ComputePipeline,
    pub(crate) main_targets: Targets,
    pub(crate) prepass_targets: Option<Targets>,
    pub(crate) cache: Option<SceneGpu>,
    pub(crate) timestamp_set: Option<wgpu::QuerySet>,
    /// Horizon quadtrees per height field, keyed by (scene key, object id, z_scale, offset).
    pub(crate) horizon_trees: Vec<(HorizonKey, crate::cull::horizon::HorizonTree)>,
    /// Isosurface pipelines and caches, created on first use.
    pub(crate) iso: Option<Box<crate::iso::render::IsoGpu>>,
}

type HorizonKey = ((u64, u64), u32, u64, [u64; 3]);

const N_TIMESTAMPS: u32 = 8;

fn storage_entry(binding: u32, read_only: bool, vis: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: vis,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32, vis: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: vis,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Checks that a scene of `nv` vertices and `ni` indices fits one vertex and one index buffer of
/// at most `max` bytes, with u32 indices and offsets: a clear error rather than a wrong image.
pub(crate) fn check_buffer_sizes(nv: u64, ni: u64, max: u64) -> Result<()> {
    if nv * 12 > max || ni * 4 > max || nv > u32::MAX as u64 || ni > u32::MAX as u64 {
        return Err(Error::Device(format!(
            "scene too large for one GPU buffer on this device: {} MiB of vertices ({nv}), {} MiB of indices ({ni}), \
             limit {} MiB per buffer and 2^32 elements; split it into several scenes or reduce its resolution",
            nv * 12 >> 20,
            ni * 4 >> 20,
            max >> 20
        )));
    }
    Ok(())
}

/// Checks an image size against the device limit.
pub fn check_size(width: u32, height: u32, max: u32) -> Result<()> {
    ensure(width >= 1, "width", || format!("width is {width}; expected 1..={max}"))?;
    ensure(height >= 1, "height", || format!("height is {height}; expected 1..={max}"))?;
    ensure(width <= max, "width", || format!("width is {width}; this device's max texture size is {max}"))?;
    ensure(height <= max, "height", || format!("height is {height}; this device's max texture size is {max}"))?;
    Ok(())
}

impl Renderer {
    /// Opens the device and builds the pipelines for `width` × `height` images.
    pub fn new(width: u32, height: u32, backend: &str) -> Result<Self> {
        // Validate the cheap things before touching the driver.
        ensure(width >= 1, "width", || format!("width is {width}; expected >= 1"))?;
        ensure(height >= 1, "height", || format!("height is {height}; expected >= 1"))?;
        let ctx = GpuContext::new(backend)?;
        check_size(width, height, ctx.limits.max_texture_dimension_2d)?;
        let d = &ctx.device;
        let vf = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
        let scene_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &[uniform_entry(0, vf), storage_entry(1, true, vf), storage_entry(2, true, vf)],
        });
        let cs = wgpu::ShaderStages::COMPUTE;
        let hist_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("histogram"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: cs,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                storage_entry(1, false, cs),
            ],
        });
        let args_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("args"),
            entries: &[
                uniform_entry(0, cs),
                storage_entry(1, true, cs),
                storage_entry(2, true, cs),
                storage_entry(3, false, cs),
            ],
        });
        let scene_shader = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("scene.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/scene.wgsl").into()),
        });
        let cull_shader = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("cull.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/cull.wgsl").into()),
        });
        let scene_pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&scene_layout)],
            immediate_size: 0,
        });
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &[wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 0,
                shader_location: 0,
            }],
        };
        let depth_state = wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            // Reverse-Z: larger is nearer.
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        };
        let make_pipeline = |label: &str, fs: &str, targets: &[Option<wgpu::ColorTargetState>]| {
            d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&scene_pl),
                vertex: wgpu::VertexState {
                    module: &scene_shader,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(vertex_layout.clone())],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(depth_state.clone()),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &scene_shader,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let main_pipeline = make_pipeline(
            "main",
            "fs_main",
            &[
                Some(wgpu::ColorTargetState { format: COLOR_FORMAT, blend: None, write_mask: wgpu::ColorWrites::ALL }),
                Some(ID_FORMAT.into()),
            ],
        );
        let prepass_pipeline = make_pipeline("prepass", "fs_id", &[Some(ID_FORMAT.into())]);
        let hist_pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("histogram"),
            bind_group_layouts: &[Some(&hist_layout)],
            immediate_size: 0,
        });
        let args_pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("args"),
            bind_group_layouts: &[Some(&args_layout)],
            immediate_size: 0,
        });
        let hist_pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("histogram"),
            layout: Some(&hist_pl),
            module: &cull_shader,
            entry_point: Some("histogram"),
            compilation_options: Default::default(),
            cache: None,
        });
        let args_pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("build_args"),
            layout: Some(&args_pl),
            module: &cull_shader,
            entry_point: Some("build_args"),
            compilation_options: Default::default(),
            cache: None,
        });
        let timestamp_set = ctx.timestamps.then(|| {
            d.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: N_TIMESTAMPS,
            })
        });
        let main_targets = Self::make_targets(d, width, height, true);
        ctx.take_error()?;
        Ok(Self {
            ctx,
            width,
            height,
            scene_layout,
            hist_layout,
            args_layout,
            main_pipeline,
            prepass_pipeline,
            hist_pipeline,
            args_pipeline,
            main_targets,
            prepass_targets: None,
            cache: None,
            timestamp_set,
            horizon_trees: Vec::new(),
            iso: None,
        })
    }

    pub fn width(&self) -> u32 {
        self.width
    }
    pub fn height(&self) -> u32 {
        self.height
    }
    pub fn adapter_info(&self) -> String {
        self.ctx.adapter_description()
    }
    pub fn max_texture_size(&self) -> u32 {
        self.ctx.limits.max_texture_dimension_2d
    }
    /// Bytes of scene geometry currently held on the GPU.
    pub fn gpu_bytes(&self) -> u64 {
        self.cache.as_ref().map_or(0, |c| c.bytes)
    }

    fn make_targets(d: &wgpu::Device, width: u32, height: u32, with_color: bool) -> Targets {
        let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
        let tex = |label: &str, format: wgpu::TextureFormat, usage: wgpu::TextureUsages| {
            d.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let ra = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let color_tex = with_color.then(|| tex("color", COLOR_FORMAT, ra | wgpu::TextureUsages::COPY_SRC));
        let id = tex("id", ID_FORMAT, ra | wgpu::TextureUsages::TEXTURE_BINDING);
        let depth_tex = tex("depth", DEPTH_FORMAT, ra | wgpu::TextureUsages::COPY_SRC);
        Targets {
            width,
            height,
            color: color_tex.as_ref().map(|t| t.create_view(&Default::default())),
            color_tex,
            id: id.create_view(&Default::default()),
            depth: depth_tex.create_view(&Default::default()),
            depth_tex,
        }
    }

    /// Uploads the scene's geometry if it changed since the last frame.
    fn upload(&mut self, scene: &Scene) -> Result<()> {
        let key = scene.geometry_key();
        if self.cache.as_ref().is_some_and(|c| c.key == key) {
            return Ok(());
        }
        self.cache = None; // free the old buffers first
        let d = &self.ctx.device;
        // Sizes first (the coarse proxies get compact copies of the vertices they use), so that
        // the geometry is written straight into mapped GPU buffers without host temporaries.
        let (mut nv, mut ni) = (0u64, 0u64);
        let mut seen: Vec<bool> = Vec::new();
        for t in scene.objects().iter().flat_map(|o| &o.tiles) {
            seen.clear();
            seen.resize(t.positions.len(), false);
            let unique = t.coarse.iter().filter(|&&k| !std::mem::replace(&mut seen[k as usize], true)).count();
            nv += (t.positions.len() + unique) as u64;
            ni += (t.fine.len() + t.coarse.len()) as u64;
        }
        check_buffer_sizes(nv, ni, self.ctx.limits.max_buffer_size)?;
        let mapped = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            (size > 0).then(|| {
                d.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: true })
            })
        };
        let vb = mapped("vertices", nv * 12, wgpu::BufferUsages::VERTEX);
        let ib = mapped("indices", ni * 4, wgpu::BufferUsages::INDEX);
        let (mut fine, mut coarse, mut tile_object, mut bbox) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        if let (Some(vb), Some(ib)) = (&vb, &ib) {
            let mut vmap = vb.slice(..).get_mapped_range_mut().map_err(map_err)?;
            let mut imap = ib.slice(..).get_mapped_range_mut().map_err(map_err)?;
            // Mapped memory is write-only: append whole runs, counting in vertices and indices.
            let (mut v, mut i) = (0usize, 0usize);
            let mut put_v = |v: &mut usize, data: &[[f32; 3]]| {
                vmap.slice(*v * 12..(*v + data.len()) * 12).copy_from_slice(bytemuck::cast_slice(data));
                *v += data.len();
            };
            let mut put_i = |i: &mut usize, data: &[u32]| {
                imap.slice(*i * 4..(*i + data.len()) * 4).copy_from_slice(bytemuck::cast_slice(data));
                *i += data.len();
            };
            let (mut remap, mut cverts, mut cidx): (Vec<u32>, Vec<[f32; 3]>, Vec<u32>) =
                (Vec::new(), Vec::new(), Vec::new());
            for (oi, o) in scene.objects().iter().enumerate() {
                for t in &o.tiles {
                    let tile = fine.len() as u32;
                    fine.push(DrawArgs {
                        index_count: t.fine.len() as u32,
                        instance_count: 1,
                        first_index: i as u32,
                        base_vertex: v as i32,
                        first_instance: tile,
                    });
                    put_v(&mut v, &t.positions);
                    put_i(&mut i, &t.fine);
                    // The coarse proxy gets its own compact copy of the vertices it uses: software
                    // rasterisers (llvmpipe) shade every vertex in an indexed draw's index range, so
                    // indexing into the fine vertices would make the prepass cost as much as a fine draw.
                    remap.clear();
                    remap.resize(t.positions.len(), u32::MAX);
                    cverts.clear();
                    cidx.clear();
                    for &k in &t.coarse {
                        let slot = &mut remap[k as usize];
                        if *slot == u32::MAX {
                            *slot = cverts.len() as u32;
                            cverts.push(t.positions[k as usize]);
                        }
                        cidx.push(*slot);
                    }
                    coarse.push(DrawArgs {
                        index_count: cidx.len() as u32,
                        instance_count: 1,
                        first_index: i as u32,
                        base_vertex: v as i32,
                        first_instance: tile,
                    });
                    put_v(&mut v, &cverts);
                    put_i(&mut i, &cidx);
                    tile_object.push(oi as u32);
                    bbox.push((
                        DVec3::from_array(t.bbox_min.map(f64::from)),
                        DVec3::from_array(t.bbox_max.map(f64::from)),
                    ));
                }
            }
            debug_assert_eq!((v as u64, i as u64), (nv, ni));
        } else {
            // No triangles anywhere: keep the tile table (all tiles empty).
            for (oi, o) in scene.objects().iter().enumerate() {
                for t in &o.tiles {
                    let tile = fine.len() as u32;
                    fine.push(DrawArgs { first_instance: tile, ..Default::default() });
                    coarse.push(DrawArgs { first_instance: tile, ..Default::default() });
                    tile_object.push(oi as u32);
                    bbox.push((
                        DVec3::from_array(t.bbox_min.map(f64::from)),
                        DVec3::from_array(t.bbox_max.map(f64::from)),
                    ));
                }
            }
        }
        for b in vb.iter().chain(ib.iter()) {
            b.unmap();
        }
        // Storage buffers may not be empty: pad with one element.
        let to = if tile_object.is_empty() { vec![0u32] } else { tile_object.clone() };
        let tob = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("tile_object"),
            contents: bytemuck::cast_slice(&to),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let bytes = nv * 12 + ni * 4 + to.len() as u64 * 4;
        self.cache = Some(SceneGpu {
            key,
            vertices: vb,
            indices: ib,
            tile_object: tob,
            tile_object_cpu: tile_object,
            fine,
            coarse,
            bbox,
            bytes,
        });
        self.ctx.take_error()
    }

    /// Renders `scene` from `camera`.
    pub fn render(&mut self, scene: &Scene, camera: &Camera, opts: &RenderOptions) -> Result<RenderOutput> {
        ensure(opts.pixel_threshold.is_finite() && opts.pixel_threshold >= 0.0, "pixel_threshold", || {
            format!("pixel_threshold is {}; expected a number >= 0", opts.pixel_threshold)
        })?;
        ensure(
            opts.prepass_scale.is_finite() && opts.prepass_scale > 0.0 && opts.prepass_scale <= 1.0,
            "prepass_scale",
            || format!("prepass_scale is {}; expected a number in (0, 1]", opts.prepass_scale),
        )?;
        match opts.culling {
            Culling::None => self.frame(scene, camera, DrawSet::All, true),
            Culling::ThreePass => self.frame(
                scene,
                camera,
                DrawSet::ThreePass { threshold: opts.pixel_threshold, scale: opts.prepass_scale },
                false,
            ),
            Culling::Oracle => {
                // The reference frame (not timed) tells which tiles are visible at all.
                let reference = self.frame(scene, camera, DrawSet::All, true)?;
                let mask: Vec<bool> = reference.tile_pixels.iter().map(|&c| c > 0).collect();
                let mut out = self.frame(scene, camera, DrawSet::Mask(mask), false)?;
                out.tile_pixels = reference.tile_pixels;
                Ok(out)
            }
            Culling::Horizon => {
                let t0 = Instant::now();
                let (mask, visited, culled, horizon) = self.horizon_mask(scene, camera);
                let cull_ms = t0.elapsed().as_secs_f64() * 1e3;
                let mut out = self.frame(scene, camera, DrawSet::Mask(mask), true)?;
                out.stats.cull_ms = cull_ms;
                out.stats.total_ms += cull_ms;
                out.stats.nodes_visited = visited;
                out.stats.nodes_culled = culled;
                out.horizon = horizon;
                Ok(out)
            }
        }
    }

    /// The frame's camera: near/far from the visible objects' bounds in render space.
    fn frame_camera(&self, scene: &Scene, camera: &Camera) -> FrameCamera {
        let zs = DVec3::new(1.0, 1.0, camera.z_scale);
        let bounds = scene.visible_bounds().map(|(lo, hi)| (lo * zs, hi * zs));
        camera.frame(scene.origin(), bounds, self.width as f64 / self.height as f64)
    }

    /// Horizon culling on the CPU: a tile mask over the whole scene (meshes: all tiles).
    fn horizon_mask(&mut self, scene: &Scene, camera: &Camera) -> (Vec<bool>, u32, u32, Option<Vec<f32>>) {
        use crate::cull::horizon::{HeightGrid, HorizonTree};
        use crate::scene::ObjectKind;
        let zs = camera.z_scale;
        let fc = self.frame_camera(scene, camera);
        let key = scene.geometry_key();
        self.horizon_trees.retain(|(k, _)| k.0 == key);
        let mut mask = Vec::with_capacity(scene.n_tiles());
        let (mut visited, mut culled, mut horizon) = (0, 0, None);
        for o in scene.objects() {
            let ObjectKind::Heightfield { nx, ny, x0, y0, dx, dy, tiles } = &o.kind else {
                mask.extend(std::iter::repeat_n(true, o.tiles.len()));
                continue;
            };
            let hk: HorizonKey = (key, o.id, zs.to_bits(), o.offset.to_array().map(f64::to_bits));
            let idx = match self.horizon_trees.iter().position(|(k, _)| *k == hk) {
                Some(i) => i,
                None => {
                    let z = o.height_grid().unwrap_or_default();
                    let zr: Vec<f32> = z.iter().map(|&v| ((v as f64 + o.offset.z) * zs) as f32).collect();
                    let grid = HeightGrid {
                        z: &zr,
                        nx: *nx,
                        ny: *ny,
                        x0: x0 + o.offset.x,
                        y0: y0 + o.offset.y,
                        dx: *dx,
                        dy: *dy,
                        tiles: *tiles,
                    };
                    self.horizon_trees.push((hk, HorizonTree::build(&grid)));
                    self.horizon_trees.len() - 1
                }
            };
            let r = self.horizon_trees[idx].1.cull(fc.view_proj, fc.eye, self.width, self.height);
            visited += r.nodes_visited;
            culled += r.nodes_culled;
            mask.extend_from_slice(&r.tile_visible);
            if horizon.is_none() {
                horizon = Some(r.horizon);
            }
        }
        (mask, visited, culled, horizon)
    }

    fn frame(&mut self, scene: &Scene, camera: &Camera, set: DrawSet, count_final: bool) -> Result<RenderOutput> {
        let t0 = Instant::now();
        self.upload(scene)?;
        let z = camera.z_scale;
        let fc = self.frame_camera(scene, camera);
        let cache = self.cache.as_ref().unwrap();
        let n_tiles = cache.fine.len();
        let objects = scene.objects();
        // Per-frame object state: offsets, colours, visibility.
        let gpu_objects: Vec<GpuObject> = if objects.is_empty() {
            vec![GpuObject::zeroed()]
        } else {
            objects
                .iter()
                .map(|o| GpuObject {
                    offset: [o.offset.x as f32, o.offset.y as f32, o.offset.z as f32, 0.0],
                    color: [o.color[0], o.color[1], o.color[2], 1.0],
                })
                .collect()
        };
        let visible: Vec<bool> = cache.tile_object_cpu.iter().map(|&oi| objects[oi as usize].visible).collect();
        let pick = |args: &[DrawArgs], keep: &dyn Fn(usize) -> bool| -> Vec<DrawArgs> {
            args.iter()
                .enumerate()
                .map(|(i, a)| if visible[i] && keep(i) { *a } else { DrawArgs { instance_count: 0, ..*a } })
                .collect()
        };
        let d = &self.ctx.device;
        let light = light_dir(&fc);
        let globals = Globals {
            view_proj: Mat4::from_cols_array(&fc.view_proj.to_cols_array().map(|v| v as f32)).to_cols_array_2d(),
            light_dir: [light.x as f32, light.y as f32, light.z as f32, 0.0],
            z_scale: z as f32,
            _pad: [0.0; 3],
        };
        let globals_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("globals"),
            contents: bytemuck::bytes_of(&globals),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let objects_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("objects"),
            contents: bytemuck::cast_slice(&gpu_objects),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let scene_bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &self.scene_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: globals_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: objects_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: cache.tile_object.as_entire_binding() },
            ],
        });
        let n_buf = n_tiles.max(1);
        let args_usage = wgpu::BufferUsages::INDIRECT
            | wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC;
        let args_init = |label: &str, a: &[DrawArgs]| {
            let a = if a.is_empty() { vec![DrawArgs::default()] } else { a.to_vec() };
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(&a),
                usage: args_usage,
            })
        };
        let counts_buf = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("counts"),
            size: 4 * n_buf as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        enc.clear_buffer(&counts_buf, 0, None);
        let ts = self.timestamp_set.as_ref();
        let ts_render = |i: u32| {
            ts.map(|q| wgpu::RenderPassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: Some(i),
                end_of_pass_write_index: Some(i + 1),
            })
        };
        let ts_compute = |i: u32| {
            ts.map(|q| wgpu::ComputePassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: Some(i),
                end_of_pass_write_index: Some(i + 1),
            })
        };
        let mut prepass_tris = 0u64;
        let mut prescale = 1.0f64;
        let final_args: wgpu::Buffer;
        let three_pass = matches!(set, DrawSet::ThreePass { .. });
        match &set {
            DrawSet::ThreePass { threshold, scale } => {
                prescale = *scale;
                let pw = ((self.width as f64 * scale).round() as u32).max(1);
                let ph = ((self.height as f64 * scale).round() as u32).max(1);
                if self.prepass_targets.as_ref().is_none_or(|t| (t.width, t.height) != (pw, ph)) {
                    self.prepass_targets = Some(Self::make_targets(d, pw, ph, false));
                }
                let pt = self.prepass_targets.as_ref().unwrap();
                let mut coarse = pick(&cache.coarse, &|_| true);
                // Front to back, so that hidden fragments fail the depth test early.
                let zscale = DVec3::new(1.0, 1.0, z);
                let dist: Vec<f64> = cache
                    .bbox
                    .iter()
                    .zip(&cache.tile_object_cpu)
                    .map(|((lo, hi), &oi)| {
                        let off = objects[oi as usize].offset;
                        let (lo, hi) = ((*lo + off) * zscale, (*hi + off) * zscale);
                        (fc.eye.clamp(lo, hi) - fc.eye).length_squared()
                    })
                    .collect();
                coarse.sort_by(|a, b| dist[a.first_instance as usize].total_cmp(&dist[b.first_instance as usize]));
                prepass_tris = coarse.iter().filter(|a| a.instance_count > 0).map(|a| a.index_count as u64 / 3).sum();
                let coarse_buf = args_init("coarse_args", &coarse);
                // Pass 1: depth + tile id of the coarse proxies.
                {
                    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some("prepass"),
                        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                            view: &pt.id,
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                                store: wgpu::StoreOp::Store,
                            },
                        })],
                        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                            view: &pt.depth,
                            depth_ops: Some(wgpu::Operations {
                                load: wgpu::LoadOp::Clear(0.0),
                                store: wgpu::StoreOp::Discard,
                            }),
                            stencil_ops: None,
                        }),
                        timestamp_writes: ts_render(0),
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    if let (Some(vb), Some(ib)) = (&cache.vertices, &cache.indices) {
                        pass.set_pipeline(&self.prepass_pipeline);
                        pass.set_bind_group(0, &scene_bg, &[]);
                        pass.set_vertex_buffer(0, vb.slice(..));
                        pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                        pass.multi_draw_indexed_indirect(&coarse_buf, 0, n_tiles as u32);
                    }
                }
                // Pass 2: exact per-tile visible-pixel histogram; pass 3a: indirect args.
                let hist_bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("histogram"),
                    layout: &self.hist_layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&pt.id) },
                        wgpu::BindGroupEntry { binding: 1, resource: counts_buf.as_entire_binding() },
                    ],
                });
                let fine_buf = args_init("fine_args", &pick(&cache.fine, &|_| true));
                final_args = d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("draw_args"),
                    size: (n_buf * std::mem::size_of::<DrawArgs>()) as u64,
                    usage: args_usage,
                    mapped_at_creation: false,
                });
                let params =
                    CullParams { n_tiles: n_tiles as u32, threshold: (threshold * scale * scale) as f32, _pad: [0; 2] };
                let params_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("cull_params"),
                    contents: bytemuck::bytes_of(&params),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                let args_bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("args"),
                    layout: &self.args_layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: params_buf.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 1, resource: counts_buf.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 2, resource: fine_buf.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 3, resource: final_args.as_entire_binding() },
                    ],
                });
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("count"),
                    timestamp_writes: ts_compute(2),
                });
                pass.set_pipeline(&self.hist_pipeline);
                pass.set_bind_group(0, &hist_bg, &[]);
                pass.dispatch_workgroups(pw.div_ceil(16), ph.div_ceil(16), 1);
                pass.set_pipeline(&self.args_pipeline);
                pass.set_bind_group(0, &args_bg, &[]);
                pass.dispatch_workgroups((n_tiles as u32).div_ceil(64).max(1), 1, 1);
            }
            DrawSet::All => final_args = args_init("draw_args", &pick(&cache.fine, &|_| true)),
            DrawSet::Mask(m) => final_args = args_init("draw_args", &pick(&cache.fine, &|i| m[i])),
        }
        // Final pass: lit fine tiles + tile ids.
        let mt = &self.main_targets;
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("draw"),
                color_attachments: &[
                    Some(wgpu::RenderPassColorAttachment {
                        view: mt.color.as_ref().unwrap(),
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: 1.0 }),
                            store: wgpu::StoreOp::Store,
                        },
                    }),
                    Some(wgpu::RenderPassColorAttachment {
                        view: &mt.id,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    }),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &mt.depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: ts_render(4),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let (Some(vb), Some(ib)) = (&cache.vertices, &cache.indices) {
                pass.set_pipeline(&self.main_pipeline);
                pass.set_bind_group(0, &scene_bg, &[]);
                pass.set_vertex_buffer(0, vb.slice(..));
                pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                pass.multi_draw_indexed_indirect(&final_args, 0, n_tiles as u32);
            }
        }
        let ts_buf = ts.map(|q| {
            let b = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 8 * N_TIMESTAMPS as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            enc.resolve_query_set(q, 0..N_TIMESTAMPS, &b, 0);
            b
        });
        self.ctx.queue.submit([enc.finish()]);
        self.ctx.wait()?;
        let total_ms = t0.elapsed().as_secs_f64() * 1e3;
        self.ctx.take_error()?;

        // Read-back (not part of the frame time).
        let t1 = Instant::now();
        let (w, h) = (self.width, self.height);
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
        // Visible pixels per tile in the final image: counted after the frame time was taken.
        if count_final {
            let hist_bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("histogram_final"),
                layout: &self.hist_layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&mt.id) },
                    wgpu::BindGroupEntry { binding: 1, resource: counts_buf.as_entire_binding() },
                ],
            });
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("count_final"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.hist_pipeline);
            pass.set_bind_group(0, &hist_bg, &[]);
            pass.dispatch_workgroups(self.width.div_ceil(16), self.height.div_ceil(16), 1);
        }
        let color_rb =
            ReadbackTexture::new(d, &mut enc, mt.color_tex.as_ref().unwrap(), w, h, 4, wgpu::TextureAspect::All);
        let depth_rb = ReadbackTexture::new(d, &mut enc, &mt.depth_tex, w, h, 4, wgpu::TextureAspect::DepthOnly);
        let read_buf = |enc: &mut wgpu::CommandEncoder, src: &wgpu::Buffer, size: u64| {
            let b = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            enc.copy_buffer_to_buffer(src, 0, &b, 0, size);
            b
        };
        let counts_rb = read_buf(&mut enc, &counts_buf, 4 * n_buf as u64);
        let args_rb = read_buf(&mut enc, &final_args, (n_buf * std::mem::size_of::<DrawArgs>()) as u64);
        let ts_rb = ts_buf.as_ref().map(|b| read_buf(&mut enc, b, 8 * N_TIMESTAMPS as u64));
        self.ctx.queue.submit([enc.finish()]);
        for b in [&color_rb.buffer, &depth_rb.buffer, &counts_rb, &args_rb].into_iter().chain(ts_rb.as_ref()) {
            b.slice(..).map_async(wgpu::MapMode::Read, |_| {});
        }
        self.ctx.wait()?;
        self.ctx.take_error()?;
        let image = color_rb.read_rows()?;
        let depth_raw: Vec<f32> = bytemuck::cast_slice(&depth_rb.read_rows()?).to_vec();
        let depth: Vec<f32> = depth_raw.par_iter().map(|&v| fc.linear_depth(v)).collect();
        let mut counts: Vec<u32> =
            bytemuck::cast_slice(&counts_rb.slice(..).get_mapped_range().map_err(map_err)?).to_vec();
        counts.truncate(n_tiles);
        let drawn_args: Vec<DrawArgs> =
            bytemuck::cast_slice(&args_rb.slice(..).get_mapped_range().map_err(map_err)?).to_vec();
        let tile_drawn: Vec<bool> =
            drawn_args[..n_tiles].iter().map(|a| a.instance_count > 0 && a.index_count > 0).collect();
        let mut stats = RenderStats {
            triangles_fine_total: cache.fine.iter().map(|a| a.index_count as u64 / 3).sum(),
            triangles_drawn: drawn_args[..n_tiles]
                .iter()
                .filter(|a| a.instance_count > 0)
                .map(|a| a.index_count as u64 / 3)
                .sum(),
            triangles_prepass: prepass_tris,
            tiles_total: n_tiles as u32,
            tiles_drawn: tile_drawn.iter().filter(|&&b| b).count() as u32,
            total_ms,
            gpu_timestamps: ts_rb.is_some(),
            ..Default::default()
        };
        if let Some(b) = &ts_rb {
            let t: Vec<u64> = bytemuck::cast_slice(&b.slice(..).get_mapped_range().map_err(map_err)?).to_vec();
            let period = self.ctx.queue.get_timestamp_period() as f64 * 1e-6;
            let span = |i: usize| if t[i + 1] > t[i] { (t[i + 1] - t[i]) as f64 * period } else { 0.0 };
            if three_pass {
                stats.prepass_ms = span(0);
                stats.count_ms = span(2);
            }
            stats.draw_ms = span(4);
        }
        let tile_pixels = if three_pass {
            // Full-image pixel units.
            let inv = 1.0 / (prescale * prescale);
            counts.iter().map(|&c| (c as f64 * inv).round() as u32).collect()
        } else {
            counts
        };
        stats.readback_ms = t1.elapsed().as_secs_f64() * 1e3;
        Ok(RenderOutput {
            width: w,
            height: h,
            image,
            depth,
            tile_pixels,
            tile_drawn,
            stats,
            near: fc.near,
            far: fc.far,
            horizon: None,
        })
    }
}

pub(crate) enum DrawSet {
    All,
    Mask(Vec<bool>),
    ThreePass { threshold: f64, scale: f64 },
}

/// Light from over the viewer's shoulder (up and to the right), so surfaces facing the camera are lit.
pub(crate) fn light_dir(fc: &FrameCamera) -> DVec3 {
    let inv = fc.view.inverse();
    let right = inv.transform_vector3(DVec3::X);
    let up = inv.transform_vector3(DVec3::Y);
    (-fc.forward + 0.6 * up + 0.3 * right).normalize()
}

/// A texture copied into a mappable buffer with 256-byte aligned rows.
pub(crate) struct ReadbackTexture {
    pub(crate) buffer: wgpu::Buffer,
    row_bytes: u32,
    padded: u32,
    height: u32,
}

impl ReadbackTexture {
    pub(crate) fn new(
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

    pub(crate) fn read_rows(&self) -> Result<Vec<u8>> {
        let data = self.buffer.slice(..).get_mapped_range().map_err(map_err)?;
        let mut out = Vec::with_capacity((self.row_bytes * self.height) as usize);
        for r in 0..self.height as usize {
            let s = r * self.padded as usize;
            out.extend_from_slice(&data[s..s + self.row_bytes as usize]);
        }
        Ok(out)
    }
}

pub(crate) fn map_err(e: impl std::fmt::Display) -> Error {
    Error::Device(format!("reading back from the GPU failed: {e}"))
}

#[cfg(test)]
mod tests;

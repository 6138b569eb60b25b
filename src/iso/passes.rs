//! The isosurface passes: pipelines (iso.wgsl), their targets, and the two steps that record and
//! submit them: the occlusion map with the cells seen ([`march`]: a compute walk per pixel through
//! the occluder depth's class grid, [`ClassGrid`]) and the lit surface ([`draw_surface`]).
//! `super::render` decides what goes into them.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;
use wgpu::util::DeviceExt;

use super::bricks::{class_counts, pack2, pack_nodes, skip_reach, BrickLevel, COARSE_SHIFT, FINE_SHIFT};
use super::march::SurfacePatch;
use crate::camera::{FrameCamera, Projection};
use crate::error::{Error, Result};
use crate::gpu::targets::{texture, COLOR_FORMAT, DEPTH_FORMAT};
use crate::gpu::{map_err, GpuContext};
use glam::{DMat4, DVec3, DVec4};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct Globals {
    pub(super) view_proj: [[f32; 4]; 4],
    pub(super) light_dir: [f32; 4],
    pub(super) color: [f32; 4],
}

pub(super) struct Targets {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) color_tex: wgpu::Texture,
    pub(super) color: wgpu::TextureView,
    pub(super) depth_tex: wgpu::Texture,
    pub(super) depth: wgpu::TextureView,
    /// The occlusion map: reverse-Z depth per pixel (row-major, row 0 = top), 0 = nothing proven.
    pub(super) map: wgpu::Buffer,
}

/// The class grid of one (isovalue, occluder depth): one byte per node, its class, whether its two
/// levels of skip bricks are skippable and its low faces' classes ([`super::bricks::pack_nodes`]),
/// with the contour bricks, where the walk runs ([`WalkData`]).
pub(super) struct ClassGrid {
    pub(super) key: (u32, u32),
    pub(super) dims: [u32; 3],
    /// `[fine shift, coarse shift, 0, 0]` (iso.wgsl `bricks`).
    pub(super) bricks: [u32; 4],
    pub(super) n_below: u32,
    pub(super) n_above: u32,
    pub(super) n_nan: u32,
    /// The node classes, 2 bits each ([`super::bricks::pack2`]), for the CPU's side of the walk
    /// (`seen::seen_cells`).
    pub(super) classes: Vec<u32>,
    /// Whether the nodes carry their low faces' classes (single cells, iso.wgsl `node_info`).
    pub(super) faces: bool,
    /// What the walk reads, on the GPU or on the host.
    pub(super) data: WalkData,
    /// The `IsoOptions::face_contours` the grid was made for.
    pub(super) contour_policy: Option<bool>,
}

/// What the walk reads: the nodes in bricks of 4³ and, for single cells with contours
/// (`IsoOptions::face_contours`), the contour bricks ([`super::bricks::contour_bricks`]) and
/// where their blocks start (`None` for coarser nodes, without contours, or, on the GPU, when
/// they exceed one storage binding).
pub(super) enum WalkData {
    /// For the compute walk ([`march`]).
    Gpu { nodes: wgpu::Buffer, contour: Option<(wgpu::Buffer, u32)> },
    /// For the host's walk (`super::walk`), with the skippable bricks' bytes
    /// ([`super::bricks::skip_byte`]), how far each reaches ([`super::bricks::skip_reach`]) and
    /// its third level of skip bricks ([`super::bricks::pack_nodes`] with `huge`).
    Host { nodes: Vec<u8>, skip: Vec<u8>, reach: Vec<u8>, huge: BrickLevel, contour: Option<(Vec<u32>, u32)> },
}

impl WalkData {
    /// Where the contour blocks start, when the walk has contour bricks.
    pub(super) fn contour_at(&self) -> Option<u32> {
        match self {
            WalkData::Gpu { contour, .. } => contour.as_ref().map(|c| c.1),
            WalkData::Host { contour, .. } => contour.as_ref().map(|c| c.1),
        }
    }

    /// Bytes of the contour bricks held for the walk.
    pub(super) fn contour_bytes(&self) -> u64 {
        match self {
            WalkData::Gpu { contour, .. } => contour.as_ref().map_or(0, |c| c.0.size()),
            WalkData::Host { contour, .. } => contour.as_ref().map_or(0, |c| 4 * c.0.len() as u64),
        }
    }

    pub(super) fn on_host(&self) -> bool {
        matches!(self, WalkData::Host { .. })
    }
}

impl ClassGrid {
    /// Completes `nodes` (x fastest, then y, z; `dims` per axis; the class in bits 0-1 and, for
    /// single cells (`faces`), the low faces' classes in bits 4-7, [`super::bricks::leaf_nodes`])
    /// with their skip bricks' flags, one byte per node in bricks of 4³
    /// ([`super::bricks::pack_nodes`]), and keeps them where the walk runs: uploaded for the
    /// compute walk, in host memory for the host's (`host`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        d: &wgpu::Device,
        key: (u32, u32),
        dims: [u32; 3],
        nodes: Vec<u8>,
        faces: bool,
        contour: Option<(Vec<u32>, usize)>,
        contour_policy: Option<bool>,
        host: bool,
    ) -> Self {
        let classes = pack2(&nodes);
        let [n_below, n_above, n_nan] = class_counts(&classes);
        let (bricked, skip, huge) = pack_nodes(&nodes, dims, host);
        drop(nodes);
        // (Without a brick that holds surface the walk has nothing to read.)
        let contour = contour.filter(|(words, at)| words.len() > *at);
        let data = if host {
            let reach = skip_reach(&skip, dims.map(|v| v.div_ceil(4)));
            let huge = huge.unwrap_or_default();
            let contour = contour.map(|(words, at)| (words, at as u32));
            WalkData::Host { nodes: bricked, skip, reach, huge, contour }
        } else {
            let nodes = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("iso_classes"),
                contents: &bricked,
                usage: wgpu::BufferUsages::STORAGE,
            });
            let contour = contour.and_then(|(words, at)| Some((storage_buffer(d, "iso_contour", &words)?, at as u32)));
            WalkData::Gpu { nodes, contour }
        };
        let bricks = [FINE_SHIFT, COARSE_SHIFT, 0, 0];
        Self { key, dims, bricks, n_below, n_above, n_nan, classes, faces, data, contour_policy }
    }
}

/// A read-only storage buffer holding `words`, or `None` when they exceed one storage binding.
fn storage_buffer(d: &wgpu::Device, label: &str, words: &[u32]) -> Option<wgpu::Buffer> {
    let bytes = std::mem::size_of_val(words) as u64;
    let limits = d.limits();
    if bytes > limits.max_storage_buffer_binding_size || bytes > limits.max_buffer_size {
        return None;
    }
    Some(d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(words),
        usage: wgpu::BufferUsages::STORAGE,
    }))
}

/// Uniforms of the map pass (iso.wgsl `MapParams`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct MapParams {
    /// The pixel rays, affine in the pixel's NDC (x, y) (iso.wgsl `ray_*`): origin on the near
    /// plane `o + x ox + y oy` and direction `d + x dx + y dy`, built in f64.
    pub(super) ray_o: [f32; 4],
    pub(super) ray_ox: [f32; 4],
    pub(super) ray_oy: [f32; 4],
    pub(super) ray_d: [f32; 4],
    pub(super) ray_dx: [f32; 4],
    pub(super) ray_dy: [f32; 4],
    pub(super) lo: [f32; 4],
    pub(super) hi: [f32; 4],
    pub(super) node: [f32; 4],
    pub(super) dims: [u32; 4],
    pub(super) size: [u32; 4],
    pub(super) occ_dims: [u32; 4],
    /// `[where the contour blocks start (0: none bound), bricks along x, along y, isovalue bits]`
    /// (iso.wgsl `contour`).
    pub(super) contour: [u32; 4],
    pub(super) bricks: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<MapParams>() == 224);

const _: () = assert!(std::mem::size_of::<Globals>() == 96);

/// Render-space frame of a volume: origin at its centre, z exaggerated.
pub(super) struct Space {
    pub(super) origin: DVec3,
    pub(super) z_scale: f64,
}

impl Space {
    pub(super) fn point(&self, p: [f64; 3]) -> DVec3 {
        let r = DVec3::from_array(p) - self.origin;
        DVec3::new(r.x, r.y, r.z * self.z_scale)
    }
}

/// The pixel rays of a frame in f64, in the volume's grid frame (`Space`, turned by the volume's
/// rotation): for NDC `(x, y)` the points `near[0] + x near[1] + y near[2]` on the near plane and
/// `far[0] + x far[1] + y far[2]` on a plane beyond the volume's box.
pub(super) struct PixelRays {
    pub(super) near: [DVec3; 3],
    pub(super) far: [DVec3; 3],
    /// Distances along the view axis of the two planes (the near plane's is the camera's near).
    pub(super) near_dist: f64,
    pub(super) far_dist: f64,
}

/// The pixel rays of `view_proj` (grid frame to clip space) for camera frame `fc` and a volume box
/// `lo..hi` (render units). A point on a plane of constant depth is affine in the pixel's NDC
/// (x, y), so the two planes' points at three NDC corners give every ray. (The f32 inverse of the
/// view-projection loses the rays when the near plane is tiny, as it is for an eye beside the
/// volume's box: the walk then followed other lines than the rasteriser's and missed visible
/// cells.)
pub(super) fn pixel_rays(view_proj: &DMat4, fc: &FrameCamera, lo: DVec3, hi: DVec3) -> PixelRays {
    let inv = view_proj.inverse();
    let unproject = |x: f64, y: f64, z: f64| {
        let q = inv * DVec4::new(x, y, z, 1.0);
        q.truncate() / q.w
    };
    let extent = (hi - lo).length().max(fc.near);
    // (In f32, as the depth buffer is: the far plane's distance is then the frame's own.)
    let z_far = match fc.projection {
        Projection::Perspective => (fc.near / (fc.near + extent)) as f32,
        Projection::Orthographic => 0.5,
    };
    let far_dist = fc.linear_depth(z_far) as f64;
    let z_far = z_far as f64;
    let plane = |z: f64| {
        let p0 = unproject(0.0, 0.0, z);
        [p0, unproject(1.0, 0.0, z) - p0, unproject(0.0, 1.0, z) - p0]
    };
    PixelRays { near: plane(1.0), far: plane(z_far), near_dist: fc.near, far_dist }
}

/// Bind-group layouts and pipelines of the isosurface passes.
pub(super) struct IsoPasses {
    pub(super) globals_layout: wgpu::BindGroupLayout,
    pub(super) map_layout: wgpu::BindGroupLayout,
    /// The walk without and with the faces' contours.
    pub(super) map_pipelines: [wgpu::ComputePipeline; 2],
    pub(super) surf_pipeline: wgpu::RenderPipeline,
    /// Bound in place of the contour bricks when a class grid has none (a binding cannot be empty).
    pub(super) no_contour: wgpu::Buffer,
}

fn buffer_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

impl IsoPasses {
    pub(super) fn new(d: &wgpu::Device) -> Self {
        let vf = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
        let vfc = vf | wgpu::ShaderStages::COMPUTE;
        let cs = wgpu::ShaderStages::COMPUTE;
        let uniform = wgpu::BufferBindingType::Uniform;
        let ro = wgpu::BufferBindingType::Storage { read_only: true };
        let rw = wgpu::BufferBindingType::Storage { read_only: false };
        let globals_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("iso_globals"),
            entries: &[buffer_entry(0, vfc, uniform)],
        });
        let map_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("iso_map"),
            entries: &[
                buffer_entry(0, cs, uniform),
                buffer_entry(1, cs, ro),
                buffer_entry(2, cs, rw),
                buffer_entry(3, cs, rw),
                buffer_entry(4, cs, ro),
            ],
        });
        let shader = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("iso.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("iso.wgsl").into()),
        });
        let pl = |label: &str, layouts: &[Option<&wgpu::BindGroupLayout>]| {
            d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: layouts,
                immediate_size: 0,
            })
        };
        let pl_globals = pl("iso_globals", &[Some(&globals_layout)]);
        let pl_map = pl("iso_map", &[Some(&globals_layout), Some(&map_layout)]);
        let depth_write = Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        });
        // GL: the `*_gl` entry points use z / w as depth, for reverse-Z precision (iso.wgsl).
        let gl = d.adapter_info().backend == wgpu::Backend::Gl;
        let entry = |name: &'static str| if gl { format!("{name}_gl") } else { name.to_string() };
        let (vs_surf, fs_surf) = (entry("vs_surf"), entry("fs_surf"));
        let prim = |cull: Option<wgpu::Face>| wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: cull,
            front_face: wgpu::FrontFace::Ccw,
            ..Default::default()
        };
        // The walk with and without the faces' contours (iso.wgsl `CONTOURS`): a CPU rasteriser
        // pays for code that no lane runs, so the walk without them leaves it out.
        let map_pipelines = [false, true].map(|contours| {
            d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(if contours { "iso_map_contours" } else { "iso_map" }),
                layout: Some(&pl_map),
                module: &shader,
                entry_point: Some("cs_map"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &[("CONTOURS", f64::from(u8::from(contours)))],
                    ..Default::default()
                },
                cache: None,
            })
        });
        const SURF_ATTRS: [wgpu::VertexAttribute; 2] = [
            wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x3, offset: 0, shader_location: 0 },
            wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x3, offset: 12, shader_location: 1 },
        ];
        let surf_pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("iso_surface"),
            layout: Some(&pl_globals),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some(&vs_surf),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 24,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &SURF_ATTRS,
                })],
            },
            primitive: prim(None),
            depth_stencil: depth_write,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some(&fs_surf),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: COLOR_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let no_contour = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("iso_no_contour"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        Self { globals_layout, map_layout, map_pipelines, surf_pipeline, no_contour }
    }
}

impl Targets {
    /// Keeps `slot` holding targets of `width` × `height`; true when it made new ones.
    pub(super) fn ensure(slot: &mut Option<Targets>, d: &wgpu::Device, width: u32, height: u32) -> bool {
        if slot.as_ref().is_some_and(|t| (t.width, t.height) == (width, height)) {
            return false;
        }
        let tex = |label: &str, format, usage| texture(d, label, width, height, format, usage);
        let ra = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let tb = wgpu::TextureUsages::TEXTURE_BINDING;
        let cs = wgpu::TextureUsages::COPY_SRC;
        let color_tex = tex("iso_color", COLOR_FORMAT, ra | cs);
        // Depth is copied back, or read through a shader where it cannot be.
        let depth_tex = tex("iso_depth", DEPTH_FORMAT, ra | tb | cs);
        let map = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("iso_map"),
            size: 4 * width as u64 * height as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let v = |t: &wgpu::Texture| t.create_view(&Default::default());
        *slot = Some(Targets { width, height, color: v(&color_tex), color_tex, depth: v(&depth_tex), depth_tex, map });
        true
    }
}

fn pass<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
    color: Option<&wgpu::TextureView>,
    depth: Option<&wgpu::TextureView>,
) -> wgpu::RenderPass<'e> {
    let colors = [color.map(|v| wgpu::RenderPassColorAttachment {
        view: v,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: 1.0 }),
            store: wgpu::StoreOp::Store,
        },
    })];
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: if color.is_some() { &colors } else { &[] },
        depth_stencil_attachment: depth.map(|view| wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// The occlusion map and the cells seen in front of it (one compute pass, one invocation per
/// pixel, see iso.wgsl): one submission, one read-back. Returns the walk's marks of the `n_cells`
/// march cells, 4 bits each (cell `i` is bits `4 (i % 8)` (seen) and `4 (i % 8) + 1..=3` (near
/// events along x, y, z) of word `i / 8`), which `render::seen_cells` resolves.
pub(super) fn march(
    ctx: &GpuContext,
    iso: &IsoPasses,
    tg: &Targets,
    globals_bg: &wgpu::BindGroup,
    grid: &ClassGrid,
    params: &wgpu::Buffer,
    n_cells: usize,
) -> Result<Vec<u32>> {
    let WalkData::Gpu { nodes, contour } = &grid.data else {
        return Err(Error::Device("the class grid is not on the GPU".into()));
    };
    let d = &ctx.device;
    let words = n_cells.div_ceil(8).max(1);
    let size = 4 * words as u64;
    let cells = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("iso_cells_seen"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let rb = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("iso_cells_rb"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("iso_map"),
        layout: &iso.map_layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: params.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: nodes.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: tg.map.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 3, resource: cells.as_entire_binding() },
            // (Read by the walk with contours only.)
            wgpu::BindGroupEntry {
                binding: 4,
                resource: contour.as_ref().map_or(&iso.no_contour, |c| &c.0).as_entire_binding(),
            },
        ],
    });
    let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("iso_march") });
    enc.clear_buffer(&cells, 0, None);
    {
        let mut p =
            enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("iso_march"), timestamp_writes: None });
        p.set_pipeline(&iso.map_pipelines[usize::from(contour.is_some())]);
        p.set_bind_group(0, globals_bg, &[]);
        p.set_bind_group(1, &bg, &[]);
        p.dispatch_workgroups(tg.width.div_ceil(8), tg.height.div_ceil(8), 1);
    }
    enc.copy_buffer_to_buffer(&cells, 0, &rb, 0, size);
    ctx.queue.submit([enc.finish()]);
    rb.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    ctx.wait()?;
    ctx.take_error()?;
    let v: Vec<u32> = bytemuck::cast_slice(&rb.slice(..).get_mapped_range().map_err(map_err)?).to_vec();
    Ok(v)
}

/// Bytes of one surface vertex (`[x, y, z, nx, ny, nz]` f32, [`pack_vertices`]) and triangle.
pub(super) const VERTEX_BYTES: u64 = 24;
pub(super) const TRIANGLE_BYTES: u64 = 12;

/// An error unless `nv` vertices and `nt` triangles fit one GPU buffer each and u32 indices.
pub(super) fn check_surface_size(ctx: &GpuContext, nv: u64, nt: u64) -> Result<()> {
    if nv > u32::MAX as u64 || nt * 3 > u32::MAX as u64 {
        return Err(Error::Device(format!("isosurface too large to index: {nv} vertices, {nt} triangles")));
    }
    let max = ctx.limits.max_buffer_size;
    if nv * VERTEX_BYTES > max || nt * TRIANGLE_BYTES > max {
        return Err(Error::Device(format!(
            "isosurface too large for one GPU buffer: {nv} vertices, {nt} triangles (limit {} MB)",
            max >> 20
        )));
    }
    Ok(())
}

/// One vector of `lens[i]` items for each `i`, back to back, part `i` written by `fill(i, part)`;
/// the parts are filled in parallel.
pub(super) fn fill_parts<T: Copy + Default + Send>(lens: &[usize], fill: impl Fn(usize, &mut [T]) + Sync) -> Vec<T> {
    let mut out = vec![T::default(); lens.iter().sum()];
    let mut parts = Vec::with_capacity(lens.len());
    let mut rest = out.as_mut_slice();
    for &n in lens {
        let (part, tail) = rest.split_at_mut(n);
        parts.push(part);
        rest = tail;
    }
    parts.into_par_iter().enumerate().for_each(|(i, part)| fill(i, part));
    out
}

/// Patch `p`'s vertices as the surface pass reads them, into `out` (one per vertex): the position
/// in render space (`space`) and the normal, whose z is divided by the exaggeration (normals
/// transform with the inverse transpose).
pub(super) fn pack_vertices(p: &SurfacePatch, space: &Space, out: &mut [[f32; 6]]) {
    for (k, v) in out.iter_mut().enumerate() {
        let q = space.point(p.positions[k]);
        let n = p.normals.get(k).copied().unwrap_or([0.0; 3]);
        *v = [q.x as f32, q.y as f32, q.z as f32, n[0], n[1], (n[2] as f64 / space.z_scale) as f32];
    }
}

/// Patch `p`'s triangles (all, or the ranges `[a, b)` of `ranges`) into `out`, their indices
/// offset by the patch's first vertex `base`.
pub(super) fn offset_triangles(p: &SurfacePatch, ranges: Option<&[[u32; 2]]>, base: u32, out: &mut [[u32; 3]]) {
    let whole = [[0, p.triangles.len() as u32]];
    let mut out = out.iter_mut();
    for &[a, b] in ranges.unwrap_or(&whole) {
        for (tri, o) in p.triangles[a as usize..b as usize].iter().zip(&mut out) {
            *o = [tri[0] + base, tri[1] + base, tri[2] + base];
        }
    }
}

/// Triangles per patch: all, or those of its `ranges`.
pub(super) fn triangle_counts(patches: &[Arc<SurfacePatch>], ranges: Option<&[Vec<[u32; 2]>]>) -> Vec<usize> {
    match ranges {
        Some(r) => r.iter().map(|r| r.iter().map(|[a, b]| (b - a) as usize).sum()).collect(),
        None => patches.iter().map(|p| p.triangles.len()).collect(),
    }
}

/// Records into `enc` the lit surface pass (clearing colour and depth) drawing the index `runs` of
/// `buffers` (vertices, indices; nothing when None), submits it and waits for the GPU.
pub(super) fn submit_surface(
    ctx: &GpuContext,
    iso: &IsoPasses,
    globals_bg: &wgpu::BindGroup,
    tg: &Targets,
    mut enc: wgpu::CommandEncoder,
    buffers: Option<(&wgpu::Buffer, &wgpu::Buffer)>,
    runs: &[std::ops::Range<u32>],
) -> Result<()> {
    {
        let mut p = pass(&mut enc, "iso_surface", Some(&tg.color), Some(&tg.depth));
        if let (Some((vb, ib)), false) = (buffers, runs.is_empty()) {
            p.set_pipeline(&iso.surf_pipeline);
            p.set_bind_group(0, globals_bg, &[]);
            p.set_vertex_buffer(0, vb.slice(..));
            p.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
            for r in runs {
                p.draw_indexed(r.clone(), 0, 0..1);
            }
        }
    }
    ctx.queue.submit([enc.finish()]);
    ctx.wait()?;
    ctx.take_error()
}

pub(super) fn index_buffer(d: &wgpu::Device, idx: &[[u32; 3]]) -> wgpu::Buffer {
    d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("iso_indices"),
        contents: bytemuck::cast_slice(idx),
        usage: wgpu::BufferUsages::INDEX,
    })
}

/// Uploads the patches (render space, f32) and draws them lit; waits for the GPU. With `ranges`,
/// only the triangles `[a, b)` of each patch's ranges are drawn (the visible cells').
pub(super) fn draw_surface(
    ctx: &GpuContext,
    iso: &IsoPasses,
    globals_bg: &wgpu::BindGroup,
    tg: &Targets,
    patches: &[Arc<SurfacePatch>],
    ranges: Option<&[Vec<[u32; 2]>]>,
    space: &Space,
) -> Result<(u64, u64)> {
    let d = &ctx.device;
    let vlens: Vec<usize> = patches.iter().map(|p| p.positions.len()).collect();
    let counts = triangle_counts(patches, ranges);
    let (nv, nt) = (vlens.iter().sum::<usize>(), counts.iter().sum::<usize>());
    check_surface_size(ctx, nv as u64, nt as u64)?;
    // Each patch's first vertex in the shared buffer.
    let base: Vec<u32> = vlens.iter().scan(0u32, |a, &n| Some(std::mem::replace(a, *a + n as u32))).collect();
    let enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("iso_surface") });
    let buffers = (nt > 0).then(|| {
        let verts = fill_parts(&vlens, |i, out| pack_vertices(&patches[i], space, out));
        let idx = fill_parts(&counts, |i, out| offset_triangles(&patches[i], ranges.map(|r| &r[i][..]), base[i], out));
        let vb = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("iso_vertices"),
            contents: bytemuck::cast_slice(&verts),
            usage: wgpu::BufferUsages::VERTEX,
        });
        (vb, index_buffer(d, &idx))
    });
    let all = 0..3 * nt as u32;
    submit_surface(ctx, iso, globals_bg, tg, enc, buffers.as_ref().map(|(v, i)| (v, i)), std::slice::from_ref(&all))?;
    Ok((nt as u64, nv as u64))
}

//! The slab test: [`Passes::record_box_test`](super::Passes::record_box_test)'s count with
//! height-field tiles' slabs (`lod::slab`) as occludees (slab_test.wgsl). Mechanics only: it
//! draws the slabs it is given, each as one instance of its tile, grown along z by the amount
//! `place` holds for the tile, and counts per tile the fragments at or in front of the depth
//! image; which tiles, and by how much, is the caller's (`cull::phases`).

use super::shader::{
    early_test_depth, float_texture_entry, shader, storage_entry, test_pipeline, with_box_wgsl, BOX_TEST_WGSL,
};
use super::targets::Targets;

/// The slab-test pipeline and its bind-group layout.
pub struct SlabTest {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
}

/// One slab vertex (`lod::slab::ShellVertex`): origin-relative (x, y, z), then as snorm8 its
/// corner's miter (x, y), its prism's steepest slope and its side (+1 top, -1 bottom).
const VERTEX: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 16,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &[
        wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x3, offset: 0, shader_location: 0 },
        wgpu::VertexAttribute { format: wgpu::VertexFormat::Snorm8x4, offset: 12, shader_location: 1 },
    ],
};

/// Tiles in one row of [`SlabDraws::place`] (slab_test.wgsl).
pub const PLACE_ROW: usize = 8192;

/// What a slab test draws and where it counts.
pub struct SlabDraws<'a> {
    /// All slabs' vertices ([`VERTEX`]) and indices (u32).
    pub vertices: &'a wgpu::Buffer,
    pub indices: &'a wgpu::Buffer,
    /// `n` indexed indirect draws, one per slab, each one instance whose first_instance is its
    /// tile, none for a tile not to test (`Passes::record_slab_gate`).
    pub draws: &'a wgpu::Buffer,
    pub n: u32,
    /// Per tile (x, y, z, grow): its object's render-space placement and its slab's growth, an
    /// RGBA32F texture of [`PLACE_ROW`] tiles to a row (`layout::rows`).
    pub place: &'a wgpu::TextureView,
}

impl SlabTest {
    /// The pipeline for `scene_layout` (group 0: the globals); `gl` compares z / w by hand;
    /// `early`: the pipeline tests on the hardware's early depth test (the image's depth bound
    /// read-only as the depth attachment, compared GreaterEqual before the fragment runs), as the
    /// box test does where it has `box_early.rs`'s pipeline, so that both draw into one pass
    /// (`Passes::begin_test_pass`). Hidden slab fragments, most of them, then never reach the
    /// shader.
    pub fn new(d: &wgpu::Device, scene_layout: &wgpu::BindGroupLayout, gl: bool, early: bool) -> Self {
        let fs = wgpu::ShaderStages::FRAGMENT;
        let vs = wgpu::ShaderStages::VERTEX;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("slab_test"),
            entries: &[float_texture_entry(0, fs), storage_entry(1, false, fs), float_texture_entry(4, vs)],
        });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("slab_test"),
            bind_group_layouts: &[Some(scene_layout), Some(&layout)],
            immediate_size: 0,
        });
        // box_test.wgsl (with box.wgsl) gives the bindings and the fragment entry points; the
        // early-depth one (box_test_early.wgsl) where the device runs it exactly, as box_early.rs.
        let mut source = format!("{}\n{}", with_box_wgsl(BOX_TEST_WGSL), include_str!("shaders/slab_test.wgsl"));
        if early {
            source.push_str(include_str!("shaders/box_test_early.wgsl"));
        }
        let module = shader(d, "slab_test.wgsl", source);
        let fs_entry = if early {
            "fs_box_early"
        } else if gl {
            "fs_box_gl"
        } else {
            "fs_box"
        };
        let depth = early.then(early_test_depth);
        let pipeline = test_pipeline(d, &pl, &module, ("vs_slab", VERTEX), fs_entry, depth);
        Self { layout, pipeline }
    }

    /// Into `pass` (`Passes::begin_test_pass` of `targets`): for every slab `slabs` draws, adds to
    /// `counts[tile]` the fragments of the slab at or in front of the depth of `targets` (drawn by
    /// an earlier pass, reverse-Z). Writes nothing to `targets`.
    pub fn draw(
        &self,
        d: &wgpu::Device,
        pass: &mut wgpu::RenderPass<'_>,
        scene_bg: &wgpu::BindGroup,
        targets: &Targets,
        slabs: &SlabDraws<'_>,
        counts: &wgpu::Buffer,
    ) {
        if slabs.n == 0 {
            return;
        }
        let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("slab_test"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&targets.depth) },
                wgpu::BindGroupEntry { binding: 1, resource: counts.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(slabs.place) },
            ],
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, scene_bg, &[]);
        pass.set_bind_group(1, &bg, &[]);
        pass.set_vertex_buffer(0, slabs.vertices.slice(..));
        pass.set_index_buffer(slabs.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.multi_draw_indexed_indirect(slabs.draws, 0, slabs.n);
    }
}

//! Structs shared with WGSL, byte for byte. Each has a compile-time size check against the
//! layout its shader declares, so a field added on one side only fails the build.

use bytemuck::{Pod, Zeroable};

/// One indexed indirect draw (wgpu's `DrawIndexedIndirectArgs`); `first_instance` carries the
/// global tile index, which the vertex shader reads as `instance_index`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug, Default, PartialEq)]
pub struct DrawArgs {
    pub index_count: u32,
    pub instance_count: u32,
    pub first_index: u32,
    pub base_vertex: i32,
    pub first_instance: u32,
}

impl DrawArgs {
    /// The same draw, switched off (instance_count 0), as the selection shader writes it.
    pub fn off(self) -> Self {
        Self { instance_count: 0, ..self }
    }
    /// Triangles this draw submits (0 when switched off).
    pub fn triangles(&self) -> u64 {
        if self.instance_count > 0 {
            self.index_count as u64 / 3
        } else {
            0
        }
    }
}

/// Per-frame uniforms of the scene passes (`Globals` in globals.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Globals {
    pub view_proj: [[f32; 4]; 4],
    /// Towards the head light, render space; w unused.
    pub light_dir: [f32; 4],
    pub z_scale: f32,
    /// Orthographic views: near / (far - near), what turns a depth into a distance for the
    /// depth-tie priorities (common.wgsl `priority_clip`); -1 for perspective views.
    pub ortho_near: f32,
    pub _pad: [f32; 2],
    /// The pixel rays of the lit pass's fine depth (draw.wgsl `fine_depth`): perspective, the
    /// eye in render space and w = 1; orthographic, the unit view direction and w = 0.
    pub eye: [f32; 4],
}

/// Per-object state read every frame (`Object` in common.wgsl): translation (world units,
/// before exaggeration), flat colour, and colour map: `cmap = (lo, 1 / (hi - lo), mode, base)`
/// with mode 0 = flat, 1 = by the vertex scalar, 2 = by the vertex's object-relative z (then lo
/// is relative to the object's origin too), and `base` the object's first row in the frame's
/// colour-map table (256 rows, then the NaN colour).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct GpuObject {
    pub offset: [f32; 4],
    pub color: [f32; 4],
    pub cmap: [f32; 4],
    /// A height field's grid for its normal map (`SceneGeometry::shading`): the object-relative
    /// (x, y) of sample (0, 0), then the row of the inverse grid transform giving the column
    /// (`cos / dx, sin / dx`).
    pub grid: [f32; 4],
    /// The row giving the grid row (`-sin / dy, cos / dy`), then `nx, ny` (a structured grid
    /// mesh's: 0, 0, then its columns and rows).
    pub grid_rows: [f32; 4],
    /// `x`: 1 + the first sample of the object's gradients (a structured grid mesh's: normals) in
    /// the normal map, 0 for none; `y`: 1 when the object's vertices carry smooth normals
    /// (`TileMesh::normals`), 2 when they carry grid coordinates (`TileMesh::grid_uv`) and its
    /// normals are in the normal map, 3 for a reservoir grid coloured per cell (its vertices
    /// carry cell coordinates, `grid::cells`); else the lit pass shades by facets. `z`: the
    /// object's depth-tie priority (`scene::Object::priority`, common.wgsl `priority_clip`); `w`:
    /// 1 for a well coloured by its log from tables (its vertices carry their stations,
    /// `TileMesh::stations`; draw.wgsl `log_scalar`), else 0.
    pub normal_map: [u32; 4],
}

/// Uniforms of the selection pass (`Params` in select.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct SelectParams {
    pub n_tiles: u32,
    /// Draws whose count is at most this are switched off (in the counted image's pixels).
    pub threshold: f32,
    pub _pad: [u32; 2],
}

/// One box instance of the box passes (box.wgsl): `lo.xyz, id, hi.xyz, 0` in render space; `id`
/// is the tile (scene box test) or the octree node (isosurface passes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug, Default)]
pub struct BoxInstance {
    pub lo: [f32; 3],
    pub id: u32,
    pub hi: [f32; 3],
    pub _pad: u32,
}

const _: () = assert!(std::mem::size_of::<DrawArgs>() == 20);
const _: () = assert!(std::mem::size_of::<BoxInstance>() == 32);
const _: () = assert!(std::mem::size_of::<Globals>() == 112);
const _: () = assert!(std::mem::size_of::<GpuObject>() == 96);
const _: () = assert!(std::mem::size_of::<SelectParams>() == 16);

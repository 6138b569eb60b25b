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
    /// The world size of one of the frame's pixels at clip w = 1 (times w: at any depth; the larger
    /// of a column's and a row's): how far the box tests grow their occludees (box_test.wgsl
    /// `grown`); then padding.
    pub pixel_world: [f32; 2],
    /// The pixel rays of the lit pass's fine depth (draw.wgsl `fine_depth`): perspective, the
    /// eye in render space and w = 1; orthographic, the unit view direction and w = 0.
    pub eye: [f32; 4],
}

/// Per-object state read every frame (`Object` in common.wgsl): translation (world units,
/// before exaggeration), flat colour, and colour map: `cmap = (lo, 1 / (hi - lo), mode, base)`
/// with mode 0 = flat, 1 = by the vertex scalar, 2 = by the vertex's object-relative z (then lo
/// is relative to the object's origin too), and `table` the object's table in the frame's
/// colour-map texture ([`ColorTables`]).
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

/// Objects in one row of the scene passes' object texture (common.wgsl `object_at`): 1365 x 6 =
/// 8190 texels, within WebGPU's guaranteed 8192.
pub const OBJECTS_PER_ROW: usize = 1365;

/// The frame's objects as the scene passes read them (common.wgsl `object_at`): an RGBA32Uint
/// texture's size (width, height) and texels, row by row, each object six texels (its fields'
/// bits in order), [`OBJECTS_PER_ROW`] to a row; at least one object (zero).
pub fn object_texels(objects: &[GpuObject]) -> ((u32, u32), Vec<[u32; 4]>) {
    let items: Vec<[[u32; 4]; 6]> = objects.iter().map(|o| bytemuck::cast(*o)).collect();
    let ((width, height), items) = rows(&items, OBJECTS_PER_ROW);
    ((width * 6, height), items.into_iter().flatten().collect())
}

/// A 2D texture of `format` (four 32-bit channels) and size `(width, height)` holding `texels`
/// row by row, for shaders to read with `textureLoad`: the tables of the lit pass and of every
/// scene pass (colour maps, objects, tiles).
pub fn table_texture<T: bytemuck::Pod>(
    ctx: &super::GpuContext,
    label: &str,
    format: wgpu::TextureFormat,
    (width, height): (u32, u32),
    texels: &[T],
) -> wgpu::Texture {
    let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
    let texture = super::targets::texture(&ctx.device, label, width, height, format, usage);
    let texel_bytes = format.block_copy_size(None).unwrap_or(16);
    ctx.queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(texels),
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(width * texel_bytes), rows_per_image: None },
        texture.size(),
    );
    texture
}

/// `items` laid out in rows of `row` for a texture: its size (width, height) and the items, the
/// last row filled with zeros; at least one item.
pub fn rows<T: Pod + Zeroable>(items: &[T], row: usize) -> ((u32, u32), Vec<T>) {
    let n = items.len().max(1);
    let (width, height) = (n.min(row), n.div_ceil(row));
    let mut out = items.to_vec();
    out.resize(width * height, T::zeroed());
    ((width as u32, height as u32), out)
}

/// Tiles in one row of the scene passes' tile texture (common.wgsl `tile_texel`): 2048 x 4 =
/// 8192 texels, WebGPU's guaranteed 2D texture width.
pub const TILES_PER_ROW: usize = 2048;

/// Every tile's four texels as the scene passes read them (common.wgsl `tile_texel`): its grid
/// (`grid`, three vec4 a tile: the plan's lattice words, bit for bit), then its object
/// (`object`, in x); RGBA32Uint, [`TILES_PER_ROW`] tiles to a row. Returns the texture's size and
/// texels; at least one tile (zero).
pub fn tile_texels(grid: &[[f32; 4]], object: &[u32]) -> ((u32, u32), Vec<[u32; 4]>) {
    let items: Vec<[[u32; 4]; 4]> = object
        .iter()
        .zip(grid.chunks_exact(3))
        .map(|(&o, g)| [g[0].map(f32::to_bits), g[1].map(f32::to_bits), g[2].map(f32::to_bits), [o, 0, 0, 0]])
        .collect();
    let ((width, height), items) = rows(&items, TILES_PER_ROW);
    ((width * 4, height), items.into_iter().flatten().collect())
}

/// The frame's colour maps as the lit pass reads them: one table per distinct map (256 rows, then
/// the NaN colour: [`TABLE_TEXELS`] texels), [`TABLES_PER_ROW`] tables side by side in each row
/// of an RGBA32F texture (draw.wgsl `base_color`), so that a texture no wider than WebGPU's
/// guaranteed 8192 texels holds them. A texture, not a storage buffer: a CPU rasteriser gathers
/// a texel fetch in one vector operation, where it loads storage lane by lane behind a branch
/// (lavapipe: a tenth of a Reek LOD frame went to the table's storage loads).
#[derive(Clone, Debug, Default)]
pub struct ColorTables {
    /// The tables' texels, table after table.
    texels: Vec<[f32; 4]>,
    /// The tables' rows (colours, NaN colour), bit for bit, to find a table already held.
    index: std::collections::HashMap<Vec<u32>, u32>,
}

/// Texels of one colour-map table: 256 rows and the NaN colour.
pub const TABLE_TEXELS: u32 = 257;
/// Tables side by side in one texture row: 31 x 257 = 7967 texels.
pub const TABLES_PER_ROW: u32 = 31;

impl ColorTables {
    /// The number of the table of map `rows` (256 RGB rows) with NaN colour `nan`, added if
    /// no table so far has the same colours.
    pub fn table(&mut self, rows: &[[f32; 3]], nan: [f32; 3]) -> u32 {
        debug_assert_eq!(rows.len() + 1, TABLE_TEXELS as usize);
        let key: Vec<u32> = rows.iter().chain(std::iter::once(&nan)).flatten().map(|v| v.to_bits()).collect();
        let next = self.index.len() as u32;
        *self.index.entry(key).or_insert_with(|| {
            let texels = rows.iter().chain(std::iter::once(&nan)).map(|r| [r[0], r[1], r[2], 1.0]);
            self.texels.extend(texels.take(TABLE_TEXELS as usize));
            next
        })
    }

    /// The texture's size (width, height) in texels; at least one texel.
    pub fn extent(&self) -> (u32, u32) {
        let n = (self.index.len() as u32).max(1);
        (n.min(TABLES_PER_ROW) * TABLE_TEXELS, n.div_ceil(TABLES_PER_ROW))
    }

    /// The texture's texels, row by row ([`Self::extent`]), tables past the last one zero.
    pub fn image(&self) -> Vec<[f32; 4]> {
        let (w, h) = self.extent();
        let mut image = vec![[0.0f32; 4]; (w * h) as usize];
        for (t, table) in self.texels.chunks(TABLE_TEXELS as usize).enumerate() {
            let t = t as u32;
            let at = ((t / TABLES_PER_ROW) * w + (t % TABLES_PER_ROW) * TABLE_TEXELS) as usize;
            image[at..at + table.len()].copy_from_slice(table);
        }
        image
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(v: f32) -> Vec<[f32; 3]> {
        (0..256).map(|i| [v, i as f32 / 255.0, 0.5]).collect()
    }

    #[test]
    fn tiles_take_four_texels_2048_to_a_row_bit_for_bit() {
        let n = TILES_PER_ROW + 3;
        let grid: Vec<[f32; 4]> = (0..3 * n).map(|i| [i as f32, -0.0, f32::from_bits(u32::MAX), 1e-40]).collect();
        let object: Vec<u32> = (0..n as u32).map(|t| t * 7).collect();
        let ((w, h), texels) = tile_texels(&grid, &object);
        assert_eq!((w, h), (8192, 2));
        assert_eq!(texels.len(), (w * h) as usize);
        for t in [0, 1, TILES_PER_ROW - 1, TILES_PER_ROW, n - 1] {
            let at = (t / TILES_PER_ROW) * w as usize + (t % TILES_PER_ROW) * 4;
            for i in 0..3 {
                assert_eq!(texels[at + i], grid[3 * t + i].map(f32::to_bits), "tile {t} vector {i}");
            }
            assert_eq!(texels[at + 3], [7 * t as u32, 0, 0, 0]);
        }
        assert_eq!(tile_texels(&[], &[]).0, (4, 1), "no tiles: one zero tile");
    }

    #[test]
    fn objects_take_six_texels_1365_to_a_row() {
        let o = |i: u32| GpuObject {
            offset: [i as f32, 0.0, 0.0, 0.0],
            color: [0.5; 4],
            cmap: [0.0, 1.0, 2.0, i as f32],
            grid: [0.0; 4],
            grid_rows: [0.0; 4],
            normal_map: [i + 1, 2, 3, 4],
        };
        let objects: Vec<GpuObject> = (0..OBJECTS_PER_ROW as u32 + 1).map(o).collect();
        let ((w, h), texels) = object_texels(&objects);
        assert_eq!((w, h), (8190, 2));
        let last = &texels[w as usize..w as usize + 6];
        assert_eq!(last[0][0], (OBJECTS_PER_ROW as f32).to_bits());
        assert_eq!(last[5], [OBJECTS_PER_ROW as u32 + 1, 2, 3, 4]);
        assert_eq!(texels[6 + 5], [2, 2, 3, 4], "object 1's normal_map");
        assert_eq!(object_texels(&[]).0, (6, 1));
    }

    #[test]
    fn rows_pad_the_last_row_with_zeros() {
        let ((w, h), v) = rows(&[1u32, 2, 3, 4, 5], 2);
        assert_eq!((w, h), (2, 3));
        assert_eq!(v, vec![1, 2, 3, 4, 5, 0]);
        assert_eq!(rows::<u32>(&[], 8).0, (1, 1));
    }

    #[test]
    fn tables_are_shared_by_equal_maps_and_placed_31_to_a_row() {
        let mut t = ColorTables::default();
        assert_eq!(t.extent(), (257, 1), "an empty set still makes a texture");
        assert_eq!(t.table(&map(0.0), [1.0, 0.0, 0.0]), 0);
        assert_eq!(t.table(&map(0.0), [1.0, 0.0, 0.0]), 0, "the same map and NaN colour: one table");
        assert_eq!(t.table(&map(0.0), [0.0, 1.0, 0.0]), 1, "another NaN colour: another table");
        for k in 2..40 {
            assert_eq!(t.table(&map(k as f32), [0.0; 3]), k);
        }
        assert_eq!(t.extent(), (31 * 257, 2));
        let image = t.image();
        let (w, _) = t.extent();
        // Table 33 (map 33.0): row 1, third table of it; its row 7 and its NaN colour.
        let at = (w + 2 * 257) as usize;
        assert_eq!(image[at + 7], [33.0, 7.0 / 255.0, 0.5, 1.0]);
        assert_eq!(image[at + 256], [0.0, 0.0, 0.0, 1.0]);
        assert_eq!(image[257 + 256], [0.0, 1.0, 0.0, 1.0], "table 1's NaN colour");
        // Past the last table (39 = row 1, table 8): zero.
        assert_eq!(image[(w + 9 * 257) as usize], [0.0; 4]);
    }
}

//! The scene's geometry on the GPU: one vertex buffer and one index buffer for every tile of
//! every object (height-field tiles as shared patterns over the normal map's heights, see
//! [`plan::Plan`]), the tile → object table, and each tile's fine, coarse and level draws.

mod plan;
mod upload;

use super::layout::DrawArgs;
use super::GpuContext;
use crate::error::{Error, Result};
use crate::scene::Scene;
use glam::DVec3;
use plan::compact_indices;
use rayon::prelude::*;

/// A tile's slab as the box tests draw it (from `SceneGeometry::slabs`, one instance whose
/// first_instance is the tile).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlabDraw {
    /// The slab (`lod::slab::Slab`).
    pub args: DrawArgs,
    /// Its gate (`lod::slab::Slab::gate`), where it has one.
    pub gate: Option<DrawArgs>,
    /// Whether the tile's levels of detail lie within their errors of the fine surface everywhere
    /// (lattice levels), so that the slab (and its gate) grown by a level's error holds that level.
    pub exact: bool,
    /// The box of the slab's and its gate's vertices (origin-relative, as `bbox`): they may
    /// reach out of the tile's box by their thickness, so the test's near-plane check uses this.
    pub bounds: (DVec3, DVec3),
}

/// GPU copy of a scene's geometry, keyed by [`Scene::geometry_key`].
pub struct SceneGeometry {
    pub key: (u64, u64),
    pub vertices: Option<wgpu::Buffer>,
    /// Per vertex, in `vertices`' order, the lit pass's second vertex stream: an f32 scalar (the
    /// tiles' `values` for colour by data; 0 for tiles without; no data as [`NO_DATA`]) and the
    /// packed smooth normal (`TileMesh::normals`; `lod::normals::NONE` for tiles without), or for
    /// a grid-shaded mesh (`grid_dims`) the packed grid coordinates (`TileMesh::grid_uv`).
    pub values: Option<wgpu::Buffer>,
    pub indices: Option<wgpu::Buffer>,
    /// Per tile, four texels of an RGBA32Uint texture (`layout::tile_texels`, common.wgsl
    /// `tile_texel`): three for the vertex stage (`tile_grid_at`): for a lattice tile (see
    /// [`plan::Plan`]) the object-relative (x, y) of its first sample and the grid's column axis;
    /// its row axis, the first sample's index in `shading` and the grid's row length (u32 bits);
    /// the first sample's index in `sample_values` (u32::MAX: no values); for other tiles
    /// u32::MAX in place of the `shading` index. Then its object (`object_at`).
    pub tiles: wgpu::Texture,
    /// Object index (position in `scene.objects()`) of every tile.
    pub tile_object_cpu: Vec<u32>,
    /// The values (colour by data) of the height fields that have them and are drawn as lattice
    /// tiles, per grid sample (`Object::value_grid`; no data as [`NO_DATA`]), object after object:
    /// what the lit pass's vertex stage reads in place of the vertex scalar (`sample_values` in
    /// draw.wgsl `sample_value`); then the tables of objects coloured per fragment
    /// (`gpu::cell_values`). f32 bits in an R32Uint texture, [`SHADING_ROW`] words to a row; one
    /// row of zeros when there are none.
    pub sample_values: wgpu::Texture,
    /// The fine (level 0) draw of every tile, in tile order.
    pub fine: Vec<DrawArgs>,
    /// The coarse proxy's draw of every tile (its own compact vertex copy).
    pub coarse: Vec<DrawArgs>,
    /// Every tile's occluder draw: for height-field tiles drawn as lattice patterns, a coarse
    /// lattice of their samples (`plan::occluder_pattern`: 8 triangles of a hole-free tile, a
    /// shared pattern; at most 32 that stop short of the holes of another); switched off (no
    /// indices) for the others. Cheaper than any proxy; for prepasses that only guess.
    pub occluder: Vec<DrawArgs>,
    /// Per tile, the draws of its LOD levels 1.. (`TileMesh::levels`, each with its own compact
    /// vertex copy) and their errors.
    pub levels: Vec<Vec<LevelDraw>>,
    /// The levels' variants by side mask ([`LevelDraw::grouped`]), one per distinct set.
    pub variant_sets: Vec<VariantSet>,
    /// Origin-relative tile bounds (no offset, no exaggeration), for front-to-back ordering.
    pub bbox: Vec<(DVec3, DVec3)>,
    /// Per tile, boxes whose union holds its fine triangles ([`tile_sub_boxes`]), origin-relative
    /// like `bbox`: the box tests' occludees of tiles drawn at level 0.
    pub sub_boxes: Vec<Vec<(DVec3, DVec3)>>,
    /// Per tile, a height-field tile's height blocks (`Object::height_blocks`, origin-relative
    /// like `bbox`): what the CPU proof of hidden tiles (`cull::hidden`) reads; None for others.
    pub height_blocks: Vec<Option<std::sync::Arc<crate::lod::blocks::HeightBlocks>>>,
    /// Every height-field tile's slab (`TileMesh::slab`, `lod::slab`), the box tests' occludee of
    /// such tiles, with its gate ([`SlabDraw`]); None for other tiles.
    pub slab_draws: Vec<Option<SlabDraw>>,
    /// The slabs' vertices (x, y, z, side) and u32 indices; None when no tile has one.
    pub slabs: Option<(wgpu::Buffer, wgpu::Buffer)>,
    /// The fine surfaces of the height fields as the lit pass samples them
    /// (`Object::shading_samples`), object after object, [`SHADING_ROW`] samples to a row of an
    /// RG32Uint texture, per sample the gradient as two f16 (x in the low half) or a structured
    /// grid mesh's packed fine normal, then the height (f32 bits; 0 for a normal). A texture, not
    /// storage: a CPU rasteriser gathers a texel fetch in one vector operation, where it loads
    /// storage lane by lane behind a branch.
    pub shading: wgpu::Texture,
    /// Per object (scene order), the first sample of its gradients in `shading`; None for objects
    /// without (meshes, grids; height fields past the normal map texture's capacity), which the
    /// lit pass shades with their facets' normals.
    pub shading_base: Vec<Option<u32>>,
    /// Per object, (columns, rows) of a structured grid mesh whose fine normals are in `shading`
    /// (`Object::grid_normals`: one sample per grid vertex, the packed normal then 0), whose
    /// vertices carry their grid coordinates in place of their normals; None for other objects.
    pub grid_dims: Vec<Option<(u32, u32)>>,
    /// Per object, one whose tiles' colouring scalars are tables in `sample_values`
    /// (`gpu::cell_values`: a reservoir grid's cell values, a well's log): its fragments look
    /// their value up (draw.wgsl `fs_cells`).
    pub table_colors: Vec<bool>,
    /// Per object, a well whose logs are such tables: its vertices carry their stations
    /// (`TileMesh::stations`) where others carry their values.
    pub log_colors: Vec<bool>,
    /// The tiles in runs, in order, covering every tile, each drawn by the lit pass with one
    /// pipeline.
    pub draw_runs: Vec<DrawRun>,
    pub bytes: u64,
    /// Per tile, its clearance (`lod::clearance`) for the objects' placements it was measured at:
    /// measured on the first frame that draws a height-field tile coarser than its fine level,
    /// again when an object has moved.
    pub(crate) clearance: std::sync::Mutex<Option<Clearance>>,
    /// Per tile drawn from vertices of its own, the vertex counts of its fine, coarse and level
    /// draws (each its own copy, in that order); empty for lattice tiles. What [`Self::patch`]
    /// checks a replaced object against.
    own_vertices: Vec<Vec<u32>>,
}

/// The objects' placements (`Object::placement` from the world's origin) and every tile's
/// clearance measured there (`SceneGeometry::clearances`).
pub type Clearance = (Vec<[f64; 3]>, std::sync::Arc<Vec<f32>>);

/// A run of consecutive tiles that the lit pass draws with one pipeline
/// (`SceneGeometry::draw_runs`, `Passes::record_draw`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DrawRun {
    pub tiles: std::ops::Range<usize>,
    /// Tiles of a grid mesh (`SceneGeometry::grid_dims`): their own fragment entry point.
    pub grid_mesh: bool,
    /// Tiles of a height field with a normal map (`SceneGeometry::shading_base`): shaded from it
    /// alone, by entry points without the meshes' varyings and branches (draw.wgsl `vs_field`).
    pub field: bool,
    /// Tiles of object `o`, a reservoir grid: in frames that see it from outside
    /// (`Scene::seen_from_outside`) its drawn faces bound its cells, wound outwards, and the lit
    /// pass culls their back faces.
    pub closed: Option<usize>,
    /// Tiles of an object coloured from tables (`SceneGeometry::table_colors`): `fs_cells`.
    pub cells: bool,
    /// Height-field tiles (`field`) that this frame draws at a coarser level than their fine one
    /// whose vertical error reaches the tile's clearance (`SceneGeometry::frame_runs`,
    /// `lod::clearance`: another object comes that close): their fragments write the fine
    /// surface's depth on their pixel's ray (draw.wgsl `fine_depth`), so that they hide and are
    /// hidden by that object as the fine tile is. Never set in `SceneGeometry::draw_runs`.
    pub fine_depth: bool,
}

/// Samples in one row of the normal map's texture ([`SceneGeometry::shading`], common.wgsl
/// `surface_sample`): WebGPU's guaranteed 2D texture width.
pub const SHADING_ROW: u32 = 8192;

/// Writes `words` (per sample: gradients or normal, height) into the normal map's texture from
/// sample `first` on, row by row.
pub(crate) fn write_shading(queue: &wgpu::Queue, texture: &wgpu::Texture, first: u64, words: &[[u32; 2]]) {
    let row = SHADING_ROW as u64;
    let mut done = 0usize;
    while done < words.len() {
        let k = first + done as u64;
        let n = ((row - k % row) as usize).min(words.len() - done);
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d { x: (k % row) as u32, y: (k / row) as u32, z: 0 },
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&words[done..done + n]),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: None, rows_per_image: None },
            wgpu::Extent3d { width: n as u32, height: 1, depth_or_array_layers: 1 },
        );
        done += n;
    }
}

/// The draw of one LOD level of a tile and its errors (`lod::levels::Level`).
#[derive(Clone, Copy, Debug)]
pub struct LevelDraw {
    pub args: DrawArgs,
    /// Geometric error, world units (not exaggerated), and its vertical part (`Level::error_z`).
    pub error: f32,
    pub error_z: f32,
    /// Shading error, a normal chord (unitless; `lod::shading`).
    pub shading_error: f32,
    /// The level's draws with sides shared coarse (`Level::grouped`, by side mask): an entry of
    /// `SceneGeometry::variant_sets`, [`NO_VARIANTS`] where the tile has none (only lattice tiles
    /// drawn from the normal map have them), and their error (vertical, world units).
    pub grouped: u32,
    pub grouped_error: f32,
}

/// [`LevelDraw::grouped`] of a level without variants.
pub const NO_VARIANTS: u32 = u32::MAX;

/// One level's draws by side mask (entry mask - 1, `lod::groups`), shared by the tiles of one
/// shape; `first_instance` is the tile's ([`SceneGeometry::variant`]).
pub type VariantSet = [DrawArgs; crate::lod::groups::VARIANTS];

/// The scalar uploaded for a NaN value (no data): WGSL may assume no NaN at run time, so no data
/// travels as the most negative f32, which the lit pass tests for (`s < -1e31`). The other
/// scalars go up clamped to ±`scene::color::SCALAR_LIMIT` (1e30, [`scalar_word`]), so an
/// interpolation with no data of weight above 3e-8 stays below the test: a triangle touching no
/// data is no data to its corners (with data up to 3.4e38 it was only where that weight passed 3 %,
/// and a sliver by each valid corner took the colour map's low end).
pub const NO_DATA: f32 = -f32::MAX;

/// A scalar as the lit pass receives it: NaN as [`NO_DATA`], the others clamped to ±1e30.
fn scalar_word(x: f32) -> f32 {
    const LIMIT: f32 = crate::scene::color::SCALAR_LIMIT as f32;
    if x.is_nan() {
        NO_DATA
    } else {
        x.clamp(-LIMIT, LIMIT)
    }
}

/// What a tile's vertices carry in the lit pass's scalar slot: a well's stations where its log is
/// a table (`log_table`), else its values.
fn scalar_slot(log_table: bool, t: &crate::lod::TileMesh) -> &[f32] {
    if log_table {
        &t.stations
    } else {
        &t.values
    }
}

/// What a tile's vertices carry in the lit pass's normal slot: a grid-shaded mesh's grid
/// coordinates, a reservoir grid's cell coordinates (`grid::cells`; it has no normals), else
/// its normals.
fn normal_slot(grid_mesh: bool, t: &crate::lod::TileMesh) -> &[u32] {
    if grid_mesh || t.normals.is_empty() {
        &t.grid_uv
    } else {
        &t.normals
    }
}

/// A tile's box as `SceneGeometry::bbox` keeps it (f64, origin-relative).
fn tile_bbox(t: &crate::lod::TileMesh) -> (DVec3, DVec3) {
    (DVec3::from_array(t.bbox_min.map(f64::from)), DVec3::from_array(t.bbox_max.map(f64::from)))
}

/// A tile's sub-boxes as `SceneGeometry::sub_boxes` keeps them: a height-field tile's quarters of
/// its height blocks (`HeightBlocks::quarter_boxes`, read off its blocks), another tile's
/// `TileMesh::occludee_boxes` (a pass over its triangles).
fn tile_sub_boxes(t: &crate::lod::TileMesh, blocks: Option<&crate::lod::blocks::HeightBlocks>) -> Vec<(DVec3, DVec3)> {
    let d = |v: [f32; 3]| DVec3::from_array(v.map(f64::from));
    let boxes = blocks.map_or_else(|| t.occludee_boxes(), |b| b.quarter_boxes());
    boxes.into_iter().map(|(l, h)| (d(l), d(h))).collect()
}

/// The second vertex stream's words of `n` vertices (`SceneGeometry::values`): the scalar (0
/// without values, no data as [`NO_DATA`]), the packed normal (none without) and the ring height
/// (`TileMesh::ring_z`, 0 without), into `out`.
fn vertex_words(n: usize, vals: &[f32], normals: &[u32], ring_z: &[f32], out: &mut Vec<[u32; 3]>) {
    out.clear();
    out.extend((0..n).map(|k| {
        let x = vals.get(k).map_or(0.0, |&x| scalar_word(x));
        let r = ring_z.get(k).copied().unwrap_or(0.0);
        [x.to_bits(), normals.get(k).copied().unwrap_or(crate::lod::normals::NONE), r.to_bits()]
    }));
}

/// A tile's draw (coarse proxy or LOD level) with its own compact copy of the vertices it uses:
/// software rasterisers (llvmpipe) shade every vertex in an indexed draw's index range, so
/// indexing into the fine vertices would make it cost as much as a fine draw.
#[derive(Default)]
struct CompactDraw {
    remap: Vec<u32>,
    idx: Vec<u32>,
    verts: Vec<[f32; 3]>,
    vals: Vec<f32>,
    normals: Vec<u32>,
    ring_z: Vec<f32>,
}

impl CompactDraw {
    /// The draw of `indices` of tile `t` (`vals`, `nrm`: the scalars and the normals or grid
    /// coordinates its vertices carry): its vertices, their scalars and normals, and the indices
    /// into them.
    fn build(&mut self, t: &crate::lod::TileMesh, (vals, nrm): (&[f32], &[u32]), indices: &[u32]) {
        let used = compact_indices(indices, t.positions.len(), &mut self.remap, &mut self.idx);
        self.verts.clear();
        self.verts.extend(used.iter().map(|&k| t.positions[k as usize]));
        self.vals.clear();
        self.vals.extend(used.iter().filter_map(|&k| vals.get(k as usize)));
        self.normals.clear();
        self.normals.extend(used.iter().filter_map(|&k| nrm.get(k as usize)));
        self.ring_z.clear();
        self.ring_z.extend(used.iter().filter_map(|&k| t.ring_z.get(k as usize)));
    }
}

/// Checks that a scene of `nv` vertices and `ni` indices fits one vertex and one index buffer of
/// at most `max` bytes, with u32 indices and offsets: a clear error rather than a wrong image.
pub fn check_buffer_sizes(nv: u64, ni: u64, max: u64) -> Result<()> {
    if nv * 12 > max || ni * 4 > max || nv > u32::MAX as u64 || ni > u32::MAX as u64 {
        return Err(Error::Device(format!(
            "scene too large for one GPU buffer on this device: {} MiB of vertices ({nv}), {} MiB of indices ({ni}), \
             limit {} MiB per buffer and 2^32 elements; split it into several scenes or reduce its resolution",
            (nv * 12) >> 20,
            (ni * 4) >> 20,
            max >> 20
        )));
    }
    Ok(())
}

impl SceneGeometry {
    pub fn n_tiles(&self) -> usize {
        self.fine.len()
    }

    /// Fine (level 0) triangles over every tile.
    pub fn fine_triangles(&self) -> u64 {
        self.fine.iter().map(|a| a.index_count as u64 / 3).sum()
    }

    /// Rewrites in place the geometry of the objects `ids` (distinct) of `scene`, whose geometry was replaced
    /// since this upload and nothing else changed ([`Scene::replaced_since`]; a moved slice), when
    /// each keeps its layout: not a height field, its tiles drawn from vertices of their own, and
    /// the same number of tiles, vertices and indices in every draw (fine, coarse, levels) and of
    /// grid normals. Their vertices, values, indices and grid normals are written through the
    /// queue, their boxes, sub-boxes and level errors replaced; then this geometry is the scene's
    /// (`key`). Returns false, having changed nothing, where an object's layout differs (the
    /// caller uploads the scene).
    pub fn patch(&mut self, ctx: &GpuContext, scene: &Scene, ids: &[u32]) -> Result<bool> {
        let (Some(vb), Some(sb), Some(ib)) = (&self.vertices, &self.values, &self.indices) else {
            return Ok(false);
        };
        if self.key.0 != scene.geometry_key().0 || self.shading_base.len() != scene.objects().len() {
            return Ok(false);
        }
        // Everything is checked and packed before anything is written.
        let mut writes: Vec<(&wgpu::Buffer, u64, Vec<u8>)> = Vec::new();
        let mut normal_writes = Vec::new();
        let mut tiles_done = Vec::new();
        let mut cd = CompactDraw::default();
        let mut words = Vec::new();
        for &id in ids {
            let Some(oi) = scene.objects().iter().position(|o| o.id == id) else { return Ok(false) };
            let o = &scene.objects()[oi];
            let first = self.tile_object_cpu.iter().position(|&x| x as usize == oi).unwrap_or(0);
            let n = self.tile_object_cpu.iter().skip(first).take_while(|&&x| x as usize == oi).count();
            // (An object coloured from tables has them in `sample_values`: uploaded afresh.)
            if n != o.tiles.len() || o.heightfield().is_some() || self.table_colors[oi] {
                return Ok(false);
            }
            match (self.grid_dims[oi], self.shading_base[oi], o.grid_normals()) {
                (Some(dims), Some(base), Some((nu, nv, normals))) if dims == (nu as u32, nv as u32) => {
                    normal_writes.push((base as u64, normals.iter().map(|&n| [n, 0]).collect::<Vec<_>>()));
                }
                (None, _, None) => {}
                _ => return Ok(false),
            }
            for (k, t) in (first..first + n).zip(&o.tiles) {
                let counts = &self.own_vertices[k];
                let draws: Vec<(&DrawArgs, &[u32])> = std::iter::once((&self.coarse[k], &t.coarse[..]))
                    .chain(self.levels[k].iter().map(|l| &l.args).zip(t.levels.iter().map(|l| &l.indices[..])))
                    .collect();
                if counts.len() != 2 + t.levels.len()
                    || self.levels[k].len() != t.levels.len()
                    || counts[0] as usize != t.positions.len()
                    || self.fine[k].index_count as usize != t.fine.len()
                {
                    return Ok(false);
                }
                let nrm = normal_slot(self.grid_dims[oi].is_some(), t);
                let mut put = |args: &DrawArgs, verts: &[[f32; 3]], words_of: (&[f32], &[u32], &[f32]), idx: &[u32]| {
                    vertex_words(verts.len(), words_of.0, words_of.1, words_of.2, &mut words);
                    let v = args.base_vertex as u64;
                    writes.push((vb, v * 12, bytemuck::cast_slice(verts).to_vec()));
                    writes.push((sb, v * 12, bytemuck::cast_slice(&words).to_vec()));
                    writes.push((ib, args.first_index as u64 * 4, bytemuck::cast_slice(idx).to_vec()));
                };
                put(&self.fine[k], &t.positions, (&t.values, nrm, &t.ring_z), &t.fine);
                for ((args, indices), &count) in draws.into_iter().zip(&counts[1..]) {
                    cd.build(t, (&t.values, nrm), indices);
                    if cd.verts.len() != count as usize || cd.idx.len() != args.index_count as usize {
                        return Ok(false);
                    }
                    put(args, &cd.verts, (&cd.vals, &cd.normals, &cd.ring_z), &cd.idx);
                }
                tiles_done.push((k, t));
            }
        }
        for (buffer, offset, data) in writes {
            if !data.is_empty() {
                ctx.queue.write_buffer(buffer, offset, &data);
            }
        }
        for (first, words) in normal_writes {
            write_shading(&ctx.queue, &self.shading, first, &words);
        }
        for (k, t) in tiles_done {
            self.bbox[k] = tile_bbox(t);
            self.sub_boxes[k] = tile_sub_boxes(t, self.height_blocks[k].as_deref());
            for (l, new) in self.levels[k].iter_mut().zip(&t.levels) {
                (l.error, l.error_z, l.shading_error) = (new.error, new.error_z, new.shading_error);
            }
        }
        // Their boxes moved: measured again on first use.
        *self.clearance.get_mut().unwrap_or_else(|e| e.into_inner()) = None;
        self.key = scene.geometry_key();
        Ok(true)
    }

    /// Squared distance from `eye` (render space) to each tile's box, with the objects' offsets
    /// and the exaggeration `z_scale` applied: the key of front-to-back orders.
    pub fn eye_distances(&self, scene: &Scene, origin: DVec3, eye: DVec3, z_scale: f64) -> Vec<f64> {
        let zs = DVec3::new(1.0, 1.0, z_scale);
        let objects = scene.objects();
        self.bbox
            .iter()
            .zip(&self.tile_object_cpu)
            .map(|((lo, hi), &oi)| {
                let off = objects[oi as usize].placement(origin);
                let (lo, hi) = ((*lo + off) * zs, (*hi + off) * zs);
                (eye.clamp(lo, hi) - eye).length_squared()
            })
            .collect()
    }
}

impl SceneGeometry {
    /// The runs of this frame's lit draws: `draw_runs`, with the runs of height fields split where
    /// a tile's draw (`draw_args`, one per tile) is a coarser level whose vertical error reaches
    /// the tile's clearance ([`Self::clearances`]), those parts `fine_depth`
    /// ([`split_coarse_fields`]). `draw_runs` itself where no height-field tile is drawn so (every
    /// exact frame: its image is what it was).
    pub fn frame_runs(&self, scene: &Scene, draw_args: &[DrawArgs]) -> std::borrow::Cow<'_, [DrawRun]> {
        let coarse = |k: usize| draw_args.get(k).is_some_and(|a| *a != self.fine[k]);
        if !self.draw_runs.iter().any(|r| r.field && r.tiles.clone().any(coarse)) {
            return std::borrow::Cow::Borrowed(&self.draw_runs);
        }
        let clearance = self.clearances(scene);
        // The drawn level's vertical error (+inf for a draw that is no level: a proxy).
        let error_z = |k: usize| self.drawn_errors(k, &draw_args[k]).map_or(f32::INFINITY, |e| e.1);
        match split_coarse_fields(&self.draw_runs, |k| coarse(k) && error_z(k) >= clearance[k]) {
            Some(runs) => std::borrow::Cow::Owned(runs),
            None => std::borrow::Cow::Borrowed(&self.draw_runs),
        }
    }

    /// Whether level `l` (1..) of height-field tile `k` lies past its chain of full borders
    /// (`lod::levels::LatticeShape`: it does not reach 0.6 × the triangles of the level before,
    /// it exists for groups) with an error that reaches the tile's `clearance`: such a level is not
    /// drawn, as the lit pass's fine depth (two steps along the pixel's ray) would miss the fine
    /// surface under so coarse a level (another object just below would show through).
    pub fn too_deep(&self, k: usize, l: usize, error: f32, clearance: &[f32]) -> bool {
        if self.height_blocks[k].is_none() || l == 0 || error < clearance.get(k).copied().unwrap_or(0.0) {
            return false;
        }
        let before = if l == 1 { self.fine[k].index_count } else { self.levels[k][l - 2].args.index_count };
        self.levels[k][l - 1].args.index_count as f64 > 0.6 * before as f64
    }

    /// The errors (world units: all, vertical) of tile `k`'s draw `d` when it is one of its levels
    /// or their variants (the group error: vertical); None for its fine draw or a proxy.
    pub fn drawn_errors(&self, k: usize, d: &DrawArgs) -> Option<(f32, f32)> {
        let levels = self.levels.get(k)?;
        if let Some(l) = levels.iter().find(|l| l.args == *d) {
            return Some((l.error, l.error_z));
        }
        (1..=levels.len())
            .find(|&l| self.is_variant(k, l, d))
            .map(|l| (levels[l - 1].grouped_error, levels[l - 1].grouped_error))
    }

    /// Tile `k`'s level `l` (1..) with the sides of `mask` (1..=15) shared coarse
    /// (`lod::groups`); None where the level has no variants.
    pub fn variant(&self, k: usize, l: usize, mask: u8) -> Option<DrawArgs> {
        let set = self.levels.get(k)?.get(l.checked_sub(1)?)?.grouped;
        let args = self.variant_sets.get(set as usize)?.get((mask as usize).checked_sub(1)?)?;
        Some(DrawArgs { first_instance: k as u32, ..*args })
    }

    /// Whether `d` is one of tile `k`'s level `l`'s variants other than the level's own list.
    pub fn is_variant(&self, k: usize, l: usize, d: &DrawArgs) -> bool {
        let level = &self.levels[k][l - 1];
        let Some(set) = self.variant_sets.get(level.grouped as usize) else { return false };
        *d != level.args
            && d.first_instance == k as u32
            && set.iter().any(|a| DrawArgs { first_instance: d.first_instance, ..*a } == *d)
    }

    /// Every tile's clearance (`lod::clearance`) with `scene`'s objects where they are now: a
    /// height-field tile's height blocks against the parts of the other objects' tiles (their
    /// height blocks; for other tiles 8 x 8 cells or 32 slices of their triangles' boxes,
    /// `TileMesh::finer_boxes`: a fault's or a well's pieces follow it), measured once per
    /// placement.
    pub fn clearances(&self, scene: &Scene) -> std::sync::Arc<Vec<f32>> {
        let objects = scene.objects();
        let placed: Vec<[f64; 3]> = objects.iter().map(|o| o.placement(DVec3::ZERO).to_array()).collect();
        let mut cache = self.clearance.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, c)) = cache.as_ref().filter(|(at, _)| *at == placed) {
            return c.clone();
        }
        let tiles: Vec<&crate::lod::TileMesh> = objects.iter().flat_map(|o| &o.tiles).collect();
        if tiles.len() != self.n_tiles() {
            return std::sync::Arc::new(vec![0.0; self.n_tiles()]); // not this scene's geometry: no clearance
        }
        let parts: Vec<crate::lod::clearance::TileParts> = tiles
            .par_iter()
            .enumerate()
            .map(|(k, t)| {
                let o = self.tile_object_cpu[k];
                let off = DVec3::from_array(placed[o as usize]);
                let f = |v: [f32; 3]| DVec3::from_array(v.map(f64::from));
                let at = |lo: [f32; 3], hi: [f32; 3]| ((f(lo) + off).to_array(), (f(hi) + off).to_array());
                let boxes = match &self.height_blocks[k] {
                    _ if t.is_empty() => Vec::new(),
                    Some(b) => b.blocks.iter().filter(|b| !b.is_empty()).map(|b| at(b.lo, b.hi)).collect(),
                    None => t.finer_boxes(8, 32).into_iter().map(|(l, h)| at(l, h)).collect(),
                };
                crate::lod::clearance::TileParts { object: o, field: self.height_blocks[k].is_some(), boxes }
            })
            .collect();
        let c = std::sync::Arc::new(crate::lod::clearance::clearances(&parts));
        *cache = Some((placed, c.clone()));
        c
    }
}

/// `runs` with each run of height-field tiles split where `coarse(tile)` changes, the coarse parts
/// `fine_depth`; None where no height-field tile is coarse.
fn split_coarse_fields(runs: &[DrawRun], coarse: impl Fn(usize) -> bool) -> Option<Vec<DrawRun>> {
    if !runs.iter().any(|r| r.field && r.tiles.clone().any(&coarse)) {
        return None;
    }
    let mut out: Vec<DrawRun> = Vec::with_capacity(runs.len() + 2);
    for r in runs {
        if !r.field {
            out.push(r.clone());
            continue;
        }
        let first = out.len();
        for k in r.tiles.clone() {
            let fine_depth = coarse(k);
            if out.len() > first && out[out.len() - 1].fine_depth == fine_depth {
                out.last_mut().expect("a run of this field").tiles.end = k + 1;
            } else {
                out.push(DrawRun { tiles: k..k + 1, fine_depth, ..r.clone() });
            }
        }
    }
    Some(out)
}

/// The lit pass's runs of tiles (`tile_object`: each tile's object, in draw order), each drawn
/// with one pipeline: consecutive tiles of the same kind (grid mesh, height field with a normal
/// map, reservoir grid object, other) in one run.
fn draw_runs(
    scene: &Scene,
    tile_object: &[u32],
    shading_base: &[Option<u32>],
    grid_dims: &[Option<(u32, u32)>],
    table_colors: &[bool],
) -> Vec<DrawRun> {
    let mut runs: Vec<DrawRun> = Vec::new();
    for (k, &oi) in tile_object.iter().enumerate() {
        let o = oi as usize;
        let grid_mesh = grid_dims[o].is_some();
        let object = &scene.objects()[o];
        let field = !grid_mesh && shading_base[o].is_some() && object.heightfield().is_some();
        let closed = object.grid().is_some().then_some(o);
        let cells = table_colors.get(o).copied().unwrap_or(false);
        let run = DrawRun { tiles: k..k + 1, grid_mesh, field, closed, cells, fine_depth: false };
        match runs.last_mut() {
            Some(r) if (r.grid_mesh, r.field, r.closed, r.cells) == (grid_mesh, field, closed, cells) => {
                r.tiles.end = k + 1
            }
            _ => runs.push(run),
        }
    }
    runs
}

#[cfg(test)]
mod run_tests;

//! The scene's geometry on the GPU: one vertex buffer and one index buffer for every tile of
//! every object (height-field tiles as shared patterns over the normal map's heights, see
//! [`Plan`]), the tile → object table, and each tile's fine, coarse and level draws.

use super::layout::DrawArgs;
use super::readback::map_err;
use super::GpuContext;
use crate::error::{Error, Result};
use crate::scene::{ObjectKind, Scene};
use glam::DVec3;
use rayon::prelude::*;
use wgpu::util::DeviceExt;

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
    /// Object index (position in `scene.objects()`) of every tile.
    pub tile_object: wgpu::Buffer,
    pub tile_object_cpu: Vec<u32>,
    /// Per tile three vec4 for the vertex stage (`tile_grid` in common.wgsl): for a lattice tile
    /// (see [`Plan`]) the object-relative (x, y) of its first sample and the grid's column axis;
    /// its row axis, the first sample's index in `shading` and the grid's row length (u32 bits);
    /// the first sample's index in `sample_values` (u32::MAX: no values). For other tiles u32::MAX
    /// in place of the `shading` index.
    pub tile_grid: wgpu::Buffer,
    /// The values (colour by data) of the height fields that have them and are drawn as lattice
    /// tiles, per grid sample (`Object::value_grid`; no data as [`NO_DATA`]), object after object:
    /// what the lit pass's vertex stage reads in place of the vertex scalar (`sample_values` in
    /// draw.wgsl). One zero word when there are none.
    pub sample_values: wgpu::Buffer,
    /// The fine (level 0) draw of every tile, in tile order.
    pub fine: Vec<DrawArgs>,
    /// The coarse proxy's draw of every tile (its own compact vertex copy).
    pub coarse: Vec<DrawArgs>,
    /// Every tile's occluder draw: for hole-free height-field tiles drawn as lattice patterns, the
    /// 8 triangles of their corner, mid-side and centre samples (a shared pattern); switched off
    /// (no indices) for the others. Cheaper than any proxy; for prepasses that only guess.
    pub occluder: Vec<DrawArgs>,
    /// Per tile, the draws of its LOD levels 1.. (`TileMesh::levels`, each with its own compact
    /// vertex copy) and their errors.
    pub levels: Vec<Vec<LevelDraw>>,
    /// Origin-relative tile bounds (no offset, no exaggeration), for front-to-back ordering.
    pub bbox: Vec<(DVec3, DVec3)>,
    /// Per tile, boxes whose union holds its fine triangles (`TileMesh::sub_boxes`, [`SUB_BOXES`]²
    /// cells), origin-relative like `bbox`: the box tests' occludees of tiles drawn at level 0.
    pub sub_boxes: Vec<Vec<(DVec3, DVec3)>>,
    /// Per tile, a height-field tile's height blocks (`Object::height_blocks`, origin-relative
    /// like `bbox`): what the CPU proof of hidden tiles (`cull::hidden`) reads; None for others.
    pub height_blocks: Vec<Option<crate::lod::blocks::HeightBlocks>>,
    /// Every height-field tile's slab (`TileMesh::slab`, `lod::slab`), the box tests' occludee of
    /// such tiles: its draw in `slabs` (one instance, first_instance = the tile) and whether its
    /// levels of detail lie within their errors of the fine surface everywhere (lattice levels),
    /// so that the slab grown by a level's error holds that level; None for other tiles.
    pub slab_draws: Vec<Option<(DrawArgs, bool)>>,
    /// The slabs' vertices (x, y, z, side) and u32 indices; None when no tile has one.
    pub slabs: Option<(wgpu::Buffer, wgpu::Buffer)>,
    /// The fine surfaces of the height fields as the lit pass samples them
    /// (`Object::shading_samples`), object after object, two words per sample: the gradient as
    /// two f16 (x in the low half) and the object-relative height's f32 bits.
    pub shading: wgpu::Buffer,
    /// Per object (scene order), the first sample of its gradients in `shading`; None for objects
    /// without (meshes, grids; height fields past the device's storage-binding limit), which the
    /// lit pass shades with their facets' normals.
    pub shading_base: Vec<Option<u32>>,
    /// Per object, (columns, rows) of a structured grid mesh whose fine normals are in `shading`
    /// (`Object::grid_normals`: one sample per grid vertex, the packed normal then 0), whose
    /// vertices carry their grid coordinates in place of their normals; None for other objects.
    pub grid_dims: Vec<Option<(u32, u32)>>,
    /// Per object, a reservoir grid whose tiles' cell values are in `sample_values`
    /// (`grid::cells`): its fragments look their cell's value up (draw.wgsl `fs_cells`).
    pub cell_colors: Vec<bool>,
    /// The tiles in runs, in order, covering every tile, each drawn by the lit pass with one
    /// pipeline.
    pub draw_runs: Vec<DrawRun>,
    pub bytes: u64,
    /// Per tile drawn from vertices of its own, the vertex counts of its fine, coarse and level
    /// draws (each its own copy, in that order); empty for lattice tiles. What [`Self::patch`]
    /// checks a replaced object against.
    own_vertices: Vec<Vec<u32>>,
}

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
    /// Tiles of a grid coloured per cell (`SceneGeometry::cell_colors`): `fs_cells`.
    pub cells: bool,
}

/// Cells per side of a tile's sub-boxes (`SceneGeometry::sub_boxes`).
pub const SUB_BOXES: usize = 2;

/// The draw of one LOD level of a tile and its errors (`lod::levels::Level`).
#[derive(Clone, Copy, Debug)]
pub struct LevelDraw {
    pub args: DrawArgs,
    /// Geometric error, world units (not exaggerated).
    pub error: f32,
    /// Shading error, a normal chord (unitless; `lod::shading`).
    pub shading_error: f32,
}

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

/// The normal map of the lit pass: every height field's shading samples and every structured
/// grid mesh's fine normals, as long as they fit one storage binding (later height fields fall
/// back to facet normals and vertex heights, later grid meshes to their vertex normals). Returns
/// the buffer, each object's first sample, and each grid mesh's grid size.
#[allow(clippy::type_complexity)]
fn upload_shading(
    ctx: &GpuContext,
    scene: &Scene,
) -> Result<(wgpu::Buffer, Vec<Option<u32>>, Vec<Option<(u32, u32)>>)> {
    let max_samples = ctx.limits.max_storage_buffer_binding_size / 8;
    let mut total = 0u64;
    let mut dims = vec![None; scene.objects().len()];
    // Per object in the map: its sample count and, for a grid mesh, its fine normals (small:
    // faults), until they are written.
    let mut parts: Vec<(usize, u64, Option<Vec<u32>>)> = Vec::new();
    let base: Vec<Option<u32>> = scene
        .objects()
        .iter()
        .enumerate()
        .map(|(oi, o)| {
            let (n, normals) = match o.kind {
                ObjectKind::Heightfield { nx, ny, .. } => ((nx * ny) as u64, None),
                _ => {
                    let (nu, nv, normals) = o.grid_normals()?;
                    dims[oi] = Some((nu as u32, nv as u32));
                    ((nu * nv) as u64, Some(normals))
                }
            };
            if total + n > max_samples {
                dims[oi] = None;
                return None;
            }
            total += n;
            parts.push((oi, n, normals));
            Some((total - n) as u32)
        })
        .collect();
    // Written in place (no staging copy where the device maps storage buffers), a few objects at
    // a time: no host copy of the whole map.
    let direct = if ctx.features.contains(wgpu::Features::MAPPABLE_PRIMARY_BUFFERS) {
        wgpu::BufferUsages::MAP_WRITE
    } else {
        wgpu::BufferUsages::empty()
    };
    let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("shading"),
        size: 8 * total.max(1),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | direct,
        mapped_at_creation: true,
    });
    {
        let mut map = buf.slice(..).get_mapped_range_mut().map_err(map_err)?;
        let h = |v: f32| u32::from(half::f16::from_f32(v).to_bits());
        let samples = |(oi, _, normals): &(usize, u64, Option<Vec<u32>>)| -> Vec<[u32; 2]> {
            match normals {
                // A grid mesh: its packed fine normal, then 0.
                Some(normals) => normals.iter().map(|&n| [n, 0]).collect(),
                None => {
                    let mut out = Vec::new();
                    scene.objects()[*oi]
                        .for_each_shading_sample(|[gx, gy, z]| out.push([h(gx) | (h(gy) << 16), z.to_bits()]));
                    out
                }
            }
        };
        // As many objects at a time as there are threads, each into a vector of its own, then
        // copied (mapped memory is write-only and stays on this thread).
        let mut at = 0usize;
        for batch in parts.chunks(rayon::current_num_threads().max(1)) {
            for words in batch.par_iter().map(samples).collect::<Vec<_>>() {
                map.slice(at * 8..(at + words.len()) * 8).copy_from_slice(bytemuck::cast_slice(&words));
                at += words.len();
            }
        }
    }
    buf.unmap();
    Ok((buf, base, dims))
}

/// The per-sample values of the height fields coloured by data (`SceneGeometry::sample_values`)
/// and each object's first sample in them, for those whose heights are in the normal map
/// (`shading_base`), as long as they fit one storage binding (later ones keep vertices of their
/// own).
/// Then the cell values of grids coloured per fragment ([`super::cell_values`]).
fn upload_values(
    ctx: &GpuContext,
    scene: &Scene,
    shading_base: &[Option<u32>],
) -> (wgpu::Buffer, Vec<Option<u32>>, super::cell_values::CellTables) {
    let max_words = ctx.limits.max_storage_buffer_binding_size / 4;
    let mut words: Vec<f32> = Vec::new();
    let base = scene
        .objects()
        .iter()
        .zip(shading_base)
        .map(|(o, b)| {
            b.as_ref()?;
            let v = o.value_grid()?;
            if (words.len() + v.len()) as u64 > max_words {
                return None;
            }
            let first = words.len() as u32;
            words.extend(v.into_iter().map(scalar_word));
            Some(first)
        })
        .collect();
    let cells = super::cell_values::append(scene, &mut words, max_words, scalar_word);
    if words.is_empty() {
        words.push(0.0);
    }
    let buf = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("sample_values"),
        contents: bytemuck::cast_slice(&words),
        usage: wgpu::BufferUsages::STORAGE,
    });
    (buf, base, cells)
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

/// The slabs of `tiles` in one vertex and one index buffer, and per tile its slab's draw with
/// whether its levels are lattice levels (`SceneGeometry::slab_draws`).
#[allow(clippy::type_complexity)]
fn upload_slabs(
    d: &wgpu::Device,
    tiles: &[&crate::lod::TileMesh],
) -> (Option<(wgpu::Buffer, wgpu::Buffer)>, Vec<Option<(DrawArgs, bool)>>) {
    let (mut verts, mut idx): (Vec<[f32; 4]>, Vec<u32>) = (Vec::new(), Vec::new());
    let draws: Vec<Option<(DrawArgs, bool)>> = tiles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let s = t.slab.as_ref()?;
            let (v, ix) = (&s.vertices, &s.indices);
            let args = DrawArgs {
                index_count: ix.len() as u32,
                instance_count: 1,
                first_index: idx.len() as u32,
                base_vertex: verts.len() as i32,
                first_instance: i as u32,
            };
            verts.extend_from_slice(v);
            idx.extend_from_slice(ix);
            Some((args, s.levels_exact))
        })
        .collect();
    if idx.is_empty() {
        return (None, draws);
    }
    let buf = |label, contents: &[u8], usage| {
        d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
    };
    let vb = buf("slab_vertices", bytemuck::cast_slice(&verts), wgpu::BufferUsages::VERTEX);
    let ib = buf("slab_indices", bytemuck::cast_slice(&idx), wgpu::BufferUsages::INDEX);
    (Some((vb, ib)), draws)
}

/// A tile's sub-boxes as `SceneGeometry::sub_boxes` keeps them.
fn tile_sub_boxes(t: &crate::lod::TileMesh) -> Vec<(DVec3, DVec3)> {
    let d = |v: [f32; 3]| DVec3::from_array(v.map(f64::from));
    t.sub_boxes(SUB_BOXES).into_iter().map(|(l, h)| (d(l), d(h))).collect()
}

/// The second vertex stream's words of `n` vertices (`SceneGeometry::values`): the scalar (0
/// without values, no data as [`NO_DATA`]) and the packed normal (none without), into `out`.
fn vertex_words(n: usize, vals: &[f32], normals: &[u32], out: &mut Vec<[u32; 2]>) {
    out.clear();
    out.extend((0..n).map(|k| {
        let x = vals.get(k).map_or(0.0, |&x| scalar_word(x));
        [x.to_bits(), normals.get(k).copied().unwrap_or(crate::lod::normals::NONE)]
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
}

impl CompactDraw {
    /// The draw of `indices` of tile `t` (`nrm`: the normals or grid coordinates its vertices
    /// carry): its vertices, their values and normals, and the indices into them.
    fn build(&mut self, t: &crate::lod::TileMesh, nrm: &[u32], indices: &[u32]) {
        let used = compact_indices(indices, t.positions.len(), &mut self.remap, &mut self.idx);
        self.verts.clear();
        self.verts.extend(used.iter().map(|&k| t.positions[k as usize]));
        self.vals.clear();
        self.vals.extend(used.iter().filter_map(|&k| t.values.get(k as usize)));
        self.normals.clear();
        self.normals.extend(used.iter().filter_map(|&k| nrm.get(k as usize)));
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

/// `indices` (into `n` vertices) renumbered into `out` over the vertices they use, which are
/// returned in first-use order; `remap` is scratch.
fn compact_indices(indices: &[u32], n: usize, remap: &mut Vec<u32>, out: &mut Vec<u32>) -> Vec<u32> {
    remap.clear();
    remap.resize(n, u32::MAX);
    out.clear();
    let mut used = Vec::new();
    for &k in indices {
        let slot = &mut remap[k as usize];
        if *slot == u32::MAX {
            *slot = used.len() as u32;
            used.push(k);
        }
        out.push(*slot);
    }
    used
}

/// A draw of a lattice tile as a pattern: compact vertices as (column, row) relative to the
/// tile's first sample, and the triangle list into them. Tiles of one size without holes share
/// theirs.
type Pattern = (Vec<[u32; 2]>, Vec<u32>);

/// The occluder of a hole-free lattice tile (`local`: its vertices' (column, row)): its corner,
/// mid-side and centre samples as 2 × 2 cells, 8 triangles wound as the tile's (1 × 1 cells on a
/// side of 2 samples); the empty pattern for a tile with holes. A first guess for prepasses whose
/// frame does not rest on their proxies ([`SceneGeometry::occluder`]).
fn occluder_pattern(t: &crate::lod::TileMesh, local: &[[u32; 2]]) -> Pattern {
    let w = local.iter().map(|p| p[0]).max().unwrap_or(0) as usize + 1;
    let h = local.iter().map(|p| p[1]).max().unwrap_or(0) as usize + 1;
    if w < 2 || h < 2 || t.fine_triangles() != 2 * (w - 1) * (h - 1) {
        return (Vec::new(), Vec::new());
    }
    let steps = |n: usize| -> Vec<u32> {
        let mut s = vec![0, ((n - 1) / 2) as u32, (n - 1) as u32];
        s.dedup();
        s
    };
    let (xs, ys) = (steps(w), steps(h));
    let verts: Vec<[u32; 2]> = ys.iter().flat_map(|&y| xs.iter().map(move |&x| [x, y])).collect();
    let k = |i: usize, j: usize| (j * xs.len() + i) as u32;
    let mut idx = Vec::new();
    for j in 0..ys.len() - 1 {
        for i in 0..xs.len() - 1 {
            let (a, b, c, d) = (k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j + 1));
            idx.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    (verts, idx)
}

/// What the upload writes, counted before any buffer exists.
///
/// A *lattice tile* is a height-field tile whose object has its heights in the normal map
/// (`SceneGeometry::shading`), its values (if any) in `SceneGeometry::sample_values` and no
/// per-vertex normals: its vertices are rebuilt by
/// the vertex stage from the tile's first sample, the grid's axes and the normal map's heights
/// (`tile_position` in common.wgsl), so its draws (fine, coarse, levels) need no vertices of
/// their own, only indices into a pattern of (column, row) vertices shared by every tile of the
/// same shape. The heights are the tiles' own f32 heights bit for bit; x and y are the corner's
/// f32 position plus column and row times the axes, in f32, within a few units in the last place
/// of the tile's extent of the vertices it replaces.
struct Plan {
    /// Per tile: the patterns of its fine, coarse and level draws (in that order) for a lattice
    /// tile, None for a tile drawn from vertices of its own.
    runs: Vec<Option<Vec<usize>>>,
    patterns: Vec<Pattern>,
    /// Three vec4 per tile (`tile_grid` in common.wgsl).
    tile_grid: Vec<[f32; 4]>,
    nv: u64,
    ni: u64,
}

impl Plan {
    /// `shading_base`: each object's first sample in the normal map; `values_base`: in the
    /// per-sample values (`SceneGeometry::sample_values`), for height fields coloured by data.
    fn new(scene: &Scene, shading_base: &[Option<u32>], values_base: &[Option<u32>]) -> Self {
        // Each tile's draws, worked out in parallel (the costly part: compacting and hashing the
        // patterns), then numbered in tile order, so the patterns are those of a serial pass. In
        // batches of tiles, so that only a batch's patterns are held besides the distinct ones.
        let tiles: Vec<(usize, &crate::lod::TileMesh)> =
            scene.objects().iter().enumerate().flat_map(|(oi, o)| o.tiles.iter().map(move |t| (oi, t))).collect();
        let mut plan = Plan { runs: Vec::new(), patterns: Vec::new(), tile_grid: Vec::new(), nv: 0, ni: 0 };
        // Pattern ids by hash (a list per hash, compared in full), in first-use order.
        let mut by_hash: std::collections::HashMap<u64, Vec<usize>> = std::collections::HashMap::new();
        for batch in tiles.chunks(PLAN_BATCH) {
            let work: Vec<TileWork> = batch
                .par_iter()
                .map_init(
                    || (Vec::new(), Vec::new()),
                    |(remap, cidx), &(oi, t)| tile_work(scene, oi, t, shading_base, values_base, remap, cidx),
                )
                .collect();
            for w in work {
                match w {
                    TileWork::Own { nv, ni } => {
                        plan.runs.push(None);
                        let none = f32::from_bits(u32::MAX);
                        plan.tile_grid.extend([[0.0; 4], [0.0, 0.0, none, 0.0], [none, 0.0, 0.0, 0.0]]);
                        plan.nv += nv;
                        plan.ni += ni;
                    }
                    TileWork::Lattice { patterns, grid } => {
                        let run = patterns
                            .into_iter()
                            .map(|(h, p)| {
                                let ids = by_hash.entry(h).or_default();
                                match ids.iter().find(|&&k| plan.patterns[k] == p) {
                                    Some(&k) => k,
                                    None => {
                                        ids.push(plan.patterns.len());
                                        plan.patterns.push(p);
                                        plan.patterns.len() - 1
                                    }
                                }
                            })
                            .collect();
                        plan.runs.push(Some(run));
                        plan.tile_grid.extend(grid);
                    }
                }
            }
        }
        for (verts, idx) in &plan.patterns {
            plan.nv += verts.len() as u64;
            plan.ni += idx.len() as u64;
        }
        plan
    }
}

/// Tiles [`Plan::new`] works out at a time.
const PLAN_BATCH: usize = 64;

/// What [`Plan::new`] needs of one tile.
enum TileWork {
    /// Drawn from vertices of its own: the vertices and indices of its draws.
    Own { nv: u64, ni: u64 },
    /// A lattice tile: the patterns (with their hashes) of its fine, coarse, level and occluder
    /// draws, and its three `tile_grid` vec4.
    Lattice { patterns: Vec<(u64, Pattern)>, grid: [[f32; 4]; 3] },
}

/// Tile `t` of object `oi` as [`Plan::new`] counts it (`remap`, `cidx`: scratch).
fn tile_work(
    scene: &Scene,
    oi: usize,
    t: &crate::lod::TileMesh,
    shading_base: &[Option<u32>],
    values_base: &[Option<u32>],
    remap: &mut Vec<u32>,
    cidx: &mut Vec<u32>,
) -> TileWork {
    use std::hash::{Hash, Hasher};
    let o = &scene.objects()[oi];
    let lattice = match (shading_base[oi], o.grid_axes()) {
        (Some(base), Some(g))
            if (t.values.is_empty() || values_base[oi].is_some()) && t.normals.is_empty() && !t.is_empty() =>
        {
            o.tile_lattice(t).map(|l| (base, g, l))
        }
        _ => None,
    };
    let Some((base, g, l)) = lattice else {
        let (mut nv, mut ni) = (t.positions.len() as u64, t.fine.len() as u64);
        let mut seen = Vec::new();
        for idx in std::iter::once(&t.coarse).chain(t.levels.iter().map(|l| &l.indices)) {
            seen.clear();
            seen.resize(t.positions.len(), false);
            nv += idx.iter().filter(|&&k| !std::mem::replace(&mut seen[k as usize], true)).count() as u64;
            ni += idx.len() as u64;
        }
        return TileWork::Own { nv, ni };
    };
    let hashed = |p: Pattern| {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        p.hash(&mut h);
        (h.finish(), p)
    };
    let draws = [&t.fine, &t.coarse].into_iter().chain(t.levels.iter().map(|l| &l.indices));
    let mut patterns: Vec<(u64, Pattern)> = draws
        .map(|idx| {
            let used = compact_indices(idx, t.positions.len(), remap, cidx);
            hashed((used.iter().map(|&k| l.local[k as usize]).collect(), cidx.clone()))
        })
        .collect();
    patterns.push(hashed(occluder_pattern(t, &l.local)));
    let corner = g.pos(l.i0, l.j0);
    let first = l.j0 * g.nx + l.i0;
    let k0 = base as usize + first;
    let v0 = values_base[oi].map_or(u32::MAX, |b| b + first as u32);
    let grid = [
        [corner[0] as f32, corner[1] as f32, g.u[0] as f32, g.u[1] as f32],
        [g.v[0] as f32, g.v[1] as f32, f32::from_bits(k0 as u32), f32::from_bits(g.nx as u32)],
        [f32::from_bits(v0), 0.0, 0.0, 0.0],
    ];
    TileWork::Lattice { patterns, grid }
}

impl SceneGeometry {
    pub fn n_tiles(&self) -> usize {
        self.fine.len()
    }

    /// Fine (level 0) triangles over every tile.
    pub fn fine_triangles(&self) -> u64 {
        self.fine.iter().map(|a| a.index_count as u64 / 3).sum()
    }

    /// Uploads `scene`'s geometry. Sizes are computed first (the coarse proxies and LOD levels get
    /// compact copies of the vertices they use; the draws of lattice tiles become shared
    /// patterns), so that the geometry is written straight into mapped GPU buffers without host
    /// temporaries beyond the patterns.
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Result<Self> {
        let d = &ctx.device;
        let (shading, shading_base, grid_dims) = upload_shading(ctx, scene)?;
        let (sample_values, values_base, cells) = upload_values(ctx, scene, &shading_base);
        let mut plan = Plan::new(scene, &shading_base, &values_base);
        // Grid tiles with cell tables (drawn from vertices of their own): the table's columns and
        // first word where the vertex stage would look for a lattice (common.wgsl `tile_grid`).
        let none = f32::from_bits(u32::MAX);
        for (t, c) in cells.tiles.iter().enumerate() {
            if let Some([first, bw, bh]) = *c {
                plan.tile_grid[3 * t + 1] = [f32::from_bits(bw), f32::from_bits(bh), none, 0.0];
                plan.tile_grid[3 * t + 2] = [none, f32::from_bits(first), 0.0, 0.0];
            }
        }
        let (nv, ni) = (plan.nv, plan.ni);
        check_buffer_sizes(nv, ni, ctx.limits.max_buffer_size)?;
        let mapped = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            (size > 0).then(|| {
                d.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: true })
            })
        };
        let direct = if ctx.features.contains(wgpu::Features::MAPPABLE_PRIMARY_BUFFERS) {
            wgpu::BufferUsages::MAP_WRITE
        } else {
            wgpu::BufferUsages::empty()
        };
        // COPY_DST: an object whose geometry is replaced in place is written by `patch`.
        let dst = wgpu::BufferUsages::COPY_DST;
        let vb = mapped("vertices", nv * 12, wgpu::BufferUsages::VERTEX | dst | direct);
        let sb = mapped("values", nv * 8, wgpu::BufferUsages::VERTEX | dst | direct);
        let ib = mapped("indices", ni * 4, wgpu::BufferUsages::INDEX | dst | direct);
        let (mut fine, mut coarse, mut tile_object, mut bbox) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut occluder = Vec::new();
        let mut levels = Vec::new();
        let mut own_vertices: Vec<Vec<u32>> = Vec::new();
        if let (Some(vb), Some(sb), Some(ib)) = (&vb, &sb, &ib) {
            let mut vmap = vb.slice(..).get_mapped_range_mut().map_err(map_err)?;
            let mut smap = sb.slice(..).get_mapped_range_mut().map_err(map_err)?;
            let mut imap = ib.slice(..).get_mapped_range_mut().map_err(map_err)?;
            // Mapped memory is write-only: append whole runs, counting in vertices and indices.
            let (mut v, mut i) = (0usize, 0usize);
            // Positions and their (scalar, normal) pairs (zeros when the tile has none), run for run.
            let mut scratch: Vec<[u32; 2]> = Vec::new();
            let mut put_v = |v: &mut usize, data: &[[f32; 3]], vals: &[f32], normals: &[u32]| {
                vmap.slice(*v * 12..(*v + data.len()) * 12).copy_from_slice(bytemuck::cast_slice(data));
                vertex_words(data.len(), vals, normals, &mut scratch);
                smap.slice(*v * 8..(*v + data.len()) * 8).copy_from_slice(bytemuck::cast_slice(&scratch));
                *v += data.len();
            };
            let mut put_i = |i: &mut usize, data: &[u32]| {
                imap.slice(*i * 4..(*i + data.len()) * 4).copy_from_slice(bytemuck::cast_slice(data));
                *i += data.len();
            };
            // The patterns first: vertices (column, row, 0) as exact floats (common.wgsl).
            let mut pattern_args = Vec::with_capacity(plan.patterns.len());
            let mut cverts: Vec<[f32; 3]> = Vec::new();
            for (verts, idx) in &plan.patterns {
                pattern_args.push(DrawArgs {
                    index_count: idx.len() as u32,
                    instance_count: 1,
                    first_index: i as u32,
                    base_vertex: v as i32,
                    first_instance: 0,
                });
                cverts.clear();
                cverts.extend(verts.iter().map(|&[a, b]| [a as f32, b as f32, 0.0]));
                put_v(&mut v, &cverts, &[], &[]);
                put_i(&mut i, idx);
            }
            let mut cd = CompactDraw::default();
            let mut runs = plan.runs.iter();
            for (oi, o) in scene.objects().iter().enumerate() {
                for t in &o.tiles {
                    let nrm = normal_slot(grid_dims[oi].is_some(), t);
                    let tile = fine.len() as u32;
                    tile_object.push(oi as u32);
                    bbox.push(tile_bbox(t));
                    if let Some(ids) = runs.next().expect("one plan per tile") {
                        let args = |p: usize| DrawArgs { first_instance: tile, ..pattern_args[p] };
                        fine.push(args(ids[0]));
                        coarse.push(args(ids[1]));
                        occluder.push(args(*ids.last().expect("fine, coarse, levels, occluder")));
                        levels.push(
                            ids[2..]
                                .iter()
                                .zip(&t.levels)
                                .map(|(&p, l)| LevelDraw {
                                    args: args(p),
                                    error: l.error,
                                    shading_error: l.shading_error,
                                })
                                .collect(),
                        );
                        own_vertices.push(Vec::new());
                        continue;
                    }
                    occluder.push(DrawArgs { first_instance: tile, ..Default::default() });
                    fine.push(DrawArgs {
                        index_count: t.fine.len() as u32,
                        instance_count: 1,
                        first_index: i as u32,
                        base_vertex: v as i32,
                        first_instance: tile,
                    });
                    put_v(&mut v, &t.positions, &t.values, nrm);
                    put_i(&mut i, &t.fine);
                    // The coarse proxy and each LOD level get their own compact copy of the
                    // vertices they use: software rasterisers (llvmpipe) shade every vertex in an
                    // indexed draw's index range, so indexing into the fine vertices would make
                    // them cost as much as a fine draw.
                    let mut counts = vec![t.positions.len() as u32];
                    let mut compact = |indices: &[u32], v: &mut usize, i: &mut usize| {
                        cd.build(t, nrm, indices);
                        counts.push(cd.verts.len() as u32);
                        let args = DrawArgs {
                            index_count: cd.idx.len() as u32,
                            instance_count: 1,
                            first_index: *i as u32,
                            base_vertex: *v as i32,
                            first_instance: tile,
                        };
                        put_v(v, &cd.verts, &cd.vals, &cd.normals);
                        put_i(i, &cd.idx);
                        args
                    };
                    coarse.push(compact(&t.coarse, &mut v, &mut i));
                    levels.push(
                        t.levels
                            .iter()
                            .map(|l| LevelDraw {
                                args: compact(&l.indices, &mut v, &mut i),
                                error: l.error,
                                shading_error: l.shading_error,
                            })
                            .collect(),
                    );
                    own_vertices.push(counts);
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
                    occluder.push(DrawArgs { first_instance: tile, ..Default::default() });
                    levels.push(Vec::new());
                    own_vertices.push(Vec::new());
                    tile_object.push(oi as u32);
                    bbox.push(tile_bbox(t));
                }
            }
        }
        for b in vb.iter().chain(sb.iter()).chain(ib.iter()) {
            b.unmap();
        }
        // Storage buffers may not be empty: pad with one element.
        let to = if tile_object.is_empty() { vec![0u32] } else { tile_object.clone() };
        let tob = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("tile_object"),
            contents: bytemuck::cast_slice(&to),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let grid = if plan.tile_grid.is_empty() { vec![[0.0f32; 4]; 3] } else { plan.tile_grid };
        let tile_grid = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("tile_grid"),
            contents: bytemuck::cast_slice(&grid),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let tiles: Vec<&crate::lod::TileMesh> = scene.objects().iter().flat_map(|o| &o.tiles).collect();
        let sub_boxes = tiles.par_iter().map(|t| tile_sub_boxes(t)).collect();
        let height_blocks = scene.objects().iter().flat_map(|o| o.height_blocks()).collect();
        let (slabs, slab_draws) = upload_slabs(d, &tiles);
        let slab_bytes = slabs.as_ref().map_or(0, |(v, i)| v.size() + i.size());
        let bytes = nv * 20 + ni * 4 + to.len() as u64 * 4 + tile_grid.size() + shading.size() + sample_values.size();
        let bytes = bytes + slab_bytes;
        let draw_runs = draw_runs(scene, &tile_object, &shading_base, &grid_dims, &cells.objects);
        ctx.take_error()?;
        Ok(Self {
            key: scene.geometry_key(),
            vertices: vb,
            values: sb,
            indices: ib,
            tile_object: tob,
            tile_object_cpu: tile_object,
            tile_grid,
            sample_values,
            fine,
            coarse,
            occluder,
            levels,
            bbox,
            sub_boxes,
            height_blocks,
            slab_draws,
            slabs,
            shading,
            shading_base,
            grid_dims,
            cell_colors: cells.objects,
            draw_runs,
            bytes,
            own_vertices,
        })
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
        let mut tiles_done = Vec::new();
        let mut cd = CompactDraw::default();
        let mut words = Vec::new();
        for &id in ids {
            let Some(oi) = scene.objects().iter().position(|o| o.id == id) else { return Ok(false) };
            let o = &scene.objects()[oi];
            let first = self.tile_object_cpu.iter().position(|&x| x as usize == oi).unwrap_or(0);
            let n = self.tile_object_cpu.iter().skip(first).take_while(|&&x| x as usize == oi).count();
            // (A grid coloured per cell has its tables in `sample_values`: uploaded afresh.)
            if n != o.tiles.len() || matches!(o.kind, ObjectKind::Heightfield { .. }) || self.cell_colors[oi] {
                return Ok(false);
            }
            match (self.grid_dims[oi], self.shading_base[oi], o.grid_normals()) {
                (Some(dims), Some(base), Some((nu, nv, normals))) if dims == (nu as u32, nv as u32) => {
                    let w: Vec<[u32; 2]> = normals.iter().map(|&n| [n, 0]).collect();
                    writes.push((&self.shading, base as u64 * 8, bytemuck::cast_slice(&w).to_vec()));
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
                let mut put = |args: &DrawArgs, verts: &[[f32; 3]], vals: &[f32], normals: &[u32], idx: &[u32]| {
                    vertex_words(verts.len(), vals, normals, &mut words);
                    let v = args.base_vertex as u64;
                    writes.push((vb, v * 12, bytemuck::cast_slice(verts).to_vec()));
                    writes.push((sb, v * 8, bytemuck::cast_slice(&words).to_vec()));
                    writes.push((ib, args.first_index as u64 * 4, bytemuck::cast_slice(idx).to_vec()));
                };
                put(&self.fine[k], &t.positions, &t.values, nrm, &t.fine);
                for ((args, indices), &count) in draws.into_iter().zip(&counts[1..]) {
                    cd.build(t, nrm, indices);
                    if cd.verts.len() != count as usize || cd.idx.len() != args.index_count as usize {
                        return Ok(false);
                    }
                    put(args, &cd.verts, &cd.vals, &cd.normals, &cd.idx);
                }
                tiles_done.push((k, t));
            }
        }
        for (buffer, offset, data) in writes {
            if !data.is_empty() {
                ctx.queue.write_buffer(buffer, offset, &data);
            }
        }
        for (k, t) in tiles_done {
            self.bbox[k] = tile_bbox(t);
            self.sub_boxes[k] = tile_sub_boxes(t);
            for (l, new) in self.levels[k].iter_mut().zip(&t.levels) {
                (l.error, l.shading_error) = (new.error, new.shading_error);
            }
        }
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

/// The lit pass's runs of tiles (`tile_object`: each tile's object, in draw order), each drawn
/// with one pipeline: consecutive tiles of the same kind (grid mesh, height field with a normal
/// map, reservoir grid object, other) in one run.
fn draw_runs(
    scene: &Scene,
    tile_object: &[u32],
    shading_base: &[Option<u32>],
    grid_dims: &[Option<(u32, u32)>],
    cell_colors: &[bool],
) -> Vec<DrawRun> {
    let mut runs: Vec<DrawRun> = Vec::new();
    for (k, &oi) in tile_object.iter().enumerate() {
        let o = oi as usize;
        let grid_mesh = grid_dims[o].is_some();
        let field = !grid_mesh
            && shading_base[o].is_some()
            && matches!(scene.objects()[o].kind, ObjectKind::Heightfield { .. });
        let closed = matches!(scene.objects()[o].kind, ObjectKind::Grid(_)).then_some(o);
        let cells = cell_colors.get(o).copied().unwrap_or(false);
        let run = DrawRun { tiles: k..k + 1, grid_mesh, field, closed, cells };
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
mod run_tests {
    use super::*;
    use crate::scene::{AddOptions, GridFrame};

    #[test]
    fn height_fields_with_a_normal_map_draw_as_fields() {
        let mut s = Scene::new();
        let z: Vec<f64> = (0..81).map(|k| (k % 9) as f64 * 0.1).collect();
        let frame = || GridFrame::new([0.0, 0.0], [10.0, 10.0]);
        s.add_heightfield(&z, 9, 9, frame(), (2, 1), None, AddOptions::new(1.0)).unwrap();
        let v = [[0.0, 0.0, -5.0], [10.0, 0.0, -5.0], [0.0, 10.0, 5.0]];
        s.add_mesh(&v, &[[0, 1, 2]], "fault", None, AddOptions::new(1.0)).unwrap();
        s.add_heightfield(&z, 9, 9, frame(), (1, 1), None, AddOptions::new(1.0)).unwrap();
        s.add_heightfield(&z, 9, 9, frame(), (1, 1), None, AddOptions::new(1.0)).unwrap();
        let tile_object: Vec<u32> =
            s.objects().iter().enumerate().flat_map(|(o, ob)| std::iter::repeat_n(o as u32, ob.tiles.len())).collect();
        assert_eq!(tile_object, [0, 0, 1, 2, 3]);
        // The last height field's normal map did not fit: it draws as a mesh (fs_main).
        let runs = draw_runs(&s, &tile_object, &[Some(0), None, Some(81), None], &[None; 4], &[false; 4]);
        let got: Vec<_> = runs.iter().map(|r| (r.tiles.clone(), r.field, r.grid_mesh)).collect();
        assert_eq!(got, [(0..2, true, false), (2..3, false, false), (3..4, true, false), (4..5, false, false)]);
        // A grid mesh is never a field.
        let (base, dims) = ([Some(0), Some(81), Some(90), Some(171)], [None, Some((2, 2)), None, None]);
        let runs = draw_runs(&s, &tile_object, &base, &dims, &[false; 4]);
        let got: Vec<_> = runs.iter().map(|r| (r.tiles.clone(), r.field, r.grid_mesh)).collect();
        assert_eq!(got, [(0..2, true, false), (2..3, false, true), (3..5, true, false)]);
    }
}

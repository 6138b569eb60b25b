//! What the upload writes, counted before any buffer exists ([`Plan`]): each tile's draws, with
//! the draws of lattice tiles as patterns shared by every tile of the same shape.

use crate::scene::Scene;
use rayon::prelude::*;

/// `indices` (into `n` vertices) renumbered into `out` over the vertices they use, which are
/// returned in first-use order; `remap` is scratch.
pub(super) fn compact_indices(indices: &[u32], n: usize, remap: &mut Vec<u32>, out: &mut Vec<u32>) -> Vec<u32> {
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
pub(super) type Pattern = (Vec<[u32; 2]>, Vec<u32>);

/// The occluder of a lattice tile (`local`: its vertices' (column, row)): a coarse lattice of its
/// samples, wound as the tile's. A hole-free tile's corner, mid-side and centre samples as 2 × 2
/// cells, 8 triangles (1 × 1 cells on a side of 2 samples); a tile with holes a lattice of 4 × 4
/// cells, of which those whose four corners are samples of the tile (not holes) are drawn: at most
/// 32 triangles that stop short of its holes, where its coarse proxy would have ~100 or more. A
/// first guess for prepasses whose frame does not rest on their proxies
/// ([`SceneGeometry::occluder`]).
fn occluder_pattern(t: &crate::lod::TileMesh, local: &[[u32; 2]]) -> Pattern {
    let w = local.iter().map(|p| p[0]).max().unwrap_or(0) as usize + 1;
    let h = local.iter().map(|p| p[1]).max().unwrap_or(0) as usize + 1;
    if w < 2 || h < 2 {
        return (Vec::new(), Vec::new());
    }
    let holes = t.fine_triangles() != 2 * (w - 1) * (h - 1);
    let cells = if holes { 4 } else { 2 };
    let steps = |n: usize| -> Vec<u32> {
        let mut s: Vec<u32> = (0..=cells).map(|k| (k * (n - 1) / cells) as u32).collect();
        s.dedup();
        s
    };
    let (xs, ys) = (steps(w), steps(h));
    let present: std::collections::HashSet<[u32; 2]> =
        if holes { local.iter().copied().collect() } else { Default::default() };
    let at = |i: usize, j: usize| !holes || present.contains(&[xs[i], ys[j]]);
    let mut verts: Vec<[u32; 2]> = Vec::new();
    let mut slot = vec![u32::MAX; xs.len() * ys.len()];
    let mut k = |i: usize, j: usize| {
        let s = &mut slot[j * xs.len() + i];
        if *s == u32::MAX {
            *s = verts.len() as u32;
            verts.push([xs[i], ys[j]]);
        }
        *s
    };
    let mut idx = Vec::new();
    for j in 0..ys.len() - 1 {
        for i in 0..xs.len() - 1 {
            if !(at(i, j) && at(i + 1, j) && at(i + 1, j + 1) && at(i, j + 1)) {
                continue;
            }
            let (a, b, c, d) = (k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j + 1));
            idx.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    if idx.is_empty() {
        verts.clear();
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
pub(super) struct Plan {
    /// Per tile: the patterns of its fine, coarse, level (each with its group variants) and
    /// occluder draws (in that order) for a lattice tile, None for a tile drawn from vertices of
    /// its own (which draws no group variants).
    pub(super) runs: Vec<Option<Vec<usize>>>,
    pub(super) patterns: Vec<Pattern>,
    /// Three vec4 per tile (`tile_grid_at` in common.wgsl; `SceneGeometry::tiles`).
    pub(super) tile_grid: Vec<[f32; 4]>,
    pub(super) nv: u64,
    pub(super) ni: u64,
}

impl Plan {
    /// `shading_base`: each object's first sample in the normal map; `values_base`: in the
    /// per-sample values (`SceneGeometry::sample_values`), for height fields coloured by data.
    pub(super) fn new(scene: &Scene, shading_base: &[Option<u32>], values_base: &[Option<u32>]) -> Self {
        // Each tile's draws, worked out in parallel (the costly part: compacting and hashing the
        // patterns), then numbered in tile order, so the patterns are those of a serial pass. In
        // batches of tiles, so that only a batch's patterns are held besides the distinct ones.
        let tiles: Vec<(usize, &crate::lod::TileMesh)> =
            scene.objects().iter().enumerate().flat_map(|(oi, o)| o.tiles.iter().map(move |t| (oi, t))).collect();
        let mut plan = Plan { runs: Vec::new(), patterns: Vec::new(), tile_grid: Vec::new(), nv: 0, ni: 0 };
        // Pattern ids by hash (a list per hash, compared in full), in first-use order.
        let mut by_hash: std::collections::HashMap<u64, Vec<usize>> = std::collections::HashMap::new();
        let mut known = KnownLists::default();
        for batch in tiles.chunks(PLAN_BATCH) {
            let work: Vec<TileWork> =
                batch.par_iter().map(|&(oi, t)| tile_work(scene, oi, t, shading_base, values_base)).collect();
            // The patterns of the lattice tiles' lists that no tile before had over the same vertices.
            let fresh: Vec<Option<Fresh>> = batch
                .par_iter()
                .zip(&work)
                .map_init(
                    || (Vec::new(), Vec::new()),
                    |(remap, cidx), (&(_, t), w)| match w {
                        TileWork::Lattice { local, .. } => {
                            Some(fresh_patterns(t, local, known.get(t, local), remap, cidx))
                        }
                        TileWork::Own { .. } => None,
                    },
                )
                .collect();
            for ((w, fresh), &(_, t)) in work.into_iter().zip(fresh).zip(batch) {
                match w {
                    TileWork::Own { nv, ni } => {
                        plan.runs.push(None);
                        let none = f32::from_bits(u32::MAX);
                        plan.tile_grid.extend([[0.0; 4], [0.0, 0.0, none, 0.0], [none, 0.0, 0.0, 0.0]]);
                        plan.nv += nv;
                        plan.ni += ni;
                    }
                    TileWork::Lattice { local, grid } => {
                        let fresh = fresh.expect("worked out for every lattice tile");
                        let run = known.run(t, local, fresh, |h, p| plan.pattern_id(&mut by_hash, h, p));
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
        plan.tile_domains(scene);
        plan
    }

    /// The id of pattern `p` (hash `h`), added when new.
    fn pattern_id(&mut self, by_hash: &mut std::collections::HashMap<u64, Vec<usize>>, h: u64, p: Pattern) -> usize {
        let ids = by_hash.entry(h).or_default();
        match ids.iter().find(|&&k| self.patterns[k] == p) {
            Some(&k) => k,
            None => {
                ids.push(self.patterns.len());
                self.patterns.push(p);
                self.patterns.len() - 1
            }
        }
    }

    /// Writes each height-field tile's samples (columns i0..=i1, rows j0..=j1) into the last two
    /// words of its third `tile_grid` vec4, as `i0 | i1 << 16` and `j0 | j1 << 16` (draw.wgsl
    /// `fine_depth` keeps its meeting points inside the tile), the first word's top bit set where
    /// the tile has holes (cells without their two fine triangles); `u32::MAX` where they are not
    /// known or do not fit 15 bits.
    fn tile_domains(&mut self, scene: &Scene) {
        let none = f32::from_bits(u32::MAX);
        let mut t = 0;
        for o in scene.objects() {
            let bounds = o.tile_sample_bounds();
            for tile in &o.tiles {
                let (ix, iy) = (tile.ix as usize, tile.iy as usize);
                let dom =
                    bounds.as_ref().filter(|(bx, by)| ix + 1 < bx.len() && iy + 1 < by.len()).and_then(|(bx, by)| {
                        let ((i0, i1), (j0, j1)) = ((bx[ix], bx[ix + 1]), (by[iy], by[iy + 1]));
                        let holes = tile.fine_triangles() != 2 * (i1 - i0) * (j1 - j0);
                        (i1 < 1 << 15 && j1 < 1 << 15).then(|| {
                            let word = |a: usize, b: usize| (a | b << 16) as u32;
                            (f32::from_bits(word(i0, i1) | u32::from(holes) << 31), f32::from_bits(word(j0, j1)))
                        })
                    });
                let (z, w) = dom.unwrap_or((none, none));
                if let Some(v) = self.tile_grid.get_mut(3 * t + 2) {
                    v[2] = z;
                    v[3] = w;
                }
                t += 1;
            }
        }
    }
}

/// Tiles [`Plan::new`] works out at a time.
const PLAN_BATCH: usize = 64;

/// What [`Plan::new`] needs of one tile.
enum TileWork {
    /// Drawn from vertices of its own: the vertices and indices of its draws.
    Own { nv: u64, ni: u64 },
    /// A lattice tile: its vertices' (column, row) (`Object::tile_lattice`) and its three
    /// `tile_grid` vec4.
    Lattice { local: Vec<[u32; 2]>, grid: [[f32; 4]; 3] },
}

/// The patterns of the lattice tiles' lists seen so far, by the vertices they index (found by the
/// fine list's address, compared in full) and each list's address: tiles of one shape share their
/// lists ([`crate::lod::share_indices`], `lod::levels::LatticeShape::shared`), so each list of a
/// shape is compacted once, whichever of its variants a tile draws.
#[derive(Default)]
struct KnownLists {
    by_fine: std::collections::HashMap<(usize, usize), Vec<Layout>>,
}

/// The vertices' (column, row) of some lattice tiles, the pattern ids of the lists compacted over
/// them (by address and length) and of their occluder.
struct Layout {
    local: Vec<[u32; 2]>,
    lists: std::collections::HashMap<(usize, usize), usize>,
    occluder: usize,
}

/// What [`fresh_patterns`] worked out of a tile: per list (fine, coarse, level lists) its pattern
/// with its hash where it was not known, and the occluder's where the layout was not.
type Fresh = (Vec<Option<(u64, Pattern)>>, Option<(u64, Pattern)>);

fn address(l: &crate::lod::Indices) -> (usize, usize) {
    (l.as_ptr() as usize, l.len())
}

/// The fine, coarse and level lists (each level followed by its group variants) of a lattice tile,
/// in the order of its run.
fn tile_lists(t: &crate::lod::TileMesh) -> impl Iterator<Item = &crate::lod::Indices> {
    [&t.fine, &t.coarse].into_iter().chain(t.level_lists())
}

impl KnownLists {
    fn get(&self, t: &crate::lod::TileMesh, local: &[[u32; 2]]) -> Option<&Layout> {
        self.by_fine.get(&address(&t.fine))?.iter().find(|l| l.local == local)
    }

    /// Tile `t`'s run (pattern ids of its lists, then its occluder's), numbering what `fresh` has
    /// that is still unknown by `id`; remembered when another tile may share the lists (its fine
    /// list is shared: a tile with holes has lists of its own, and keeping its samples would only
    /// cost memory).
    fn run(
        &mut self,
        t: &crate::lod::TileMesh,
        local: Vec<[u32; 2]>,
        (lists, occluder): Fresh,
        mut id: impl FnMut(u64, Pattern) -> usize,
    ) -> Vec<usize> {
        let keep = std::sync::Arc::strong_count(&t.fine) > 1;
        let at = self.by_fine.get(&address(&t.fine)).and_then(|v| v.iter().position(|l| l.local == local));
        let mut layout = match at {
            Some(k) => self.by_fine.get_mut(&address(&t.fine)).expect("found above").swap_remove(k),
            None => {
                // `known` only grows: a layout unknown now was unknown when `fresh` ran.
                let (h, p) = occluder.expect("worked out with the layout");
                Layout { local, lists: Default::default(), occluder: id(h, p) }
            }
        };
        let mut run: Vec<usize> = tile_lists(t)
            .zip(lists)
            .map(|(l, p)| match layout.lists.get(&address(l)) {
                Some(&k) => k,
                None => {
                    let (h, p) = p.expect("worked out where unknown");
                    let k = id(h, p);
                    layout.lists.insert(address(l), k);
                    k
                }
            })
            .collect();
        run.push(layout.occluder);
        if keep {
            self.by_fine.entry(address(&t.fine)).or_default().push(layout);
        }
        run
    }
}

/// The patterns of lattice tile `t`'s lists (and occluder) that `known` (the layout of its vertices
/// `local`, if seen) does not hold ([`tile_patterns`]).
fn fresh_patterns(
    t: &crate::lod::TileMesh,
    local: &[[u32; 2]],
    known: Option<&Layout>,
    remap: &mut Vec<u32>,
    cidx: &mut Vec<u32>,
) -> Fresh {
    let lists = tile_lists(t)
        .map(|l| match known.and_then(|k| k.lists.get(&address(l))) {
            Some(_) => None,
            None => Some(list_pattern(t, l, local, remap, cidx)),
        })
        .collect();
    (lists, known.is_none().then(|| hashed(occluder_pattern(t, local))))
}

fn hashed(p: Pattern) -> (u64, Pattern) {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    p.hash(&mut h);
    (h.finish(), p)
}

/// The pattern (with its hash) of list `idx` of lattice tile `t` (`local`: its vertices' (column,
/// row); `remap`, `cidx`: scratch).
fn list_pattern(
    t: &crate::lod::TileMesh,
    idx: &[u32],
    local: &[[u32; 2]],
    remap: &mut Vec<u32>,
    cidx: &mut Vec<u32>,
) -> (u64, Pattern) {
    let used = compact_indices(idx, t.positions.len(), remap, cidx);
    hashed((used.iter().map(|&k| local[k as usize]).collect(), cidx.clone()))
}

/// Tile `t` of object `oi` as [`Plan::new`] counts it: its lattice when it is a lattice tile.
fn tile_work(
    scene: &Scene,
    oi: usize,
    t: &crate::lod::TileMesh,
    shading_base: &[Option<u32>],
    values_base: &[Option<u32>],
) -> TileWork {
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
    let corner = g.pos(l.i0, l.j0);
    let first = l.j0 * g.nx + l.i0;
    let k0 = base as usize + first;
    let v0 = values_base[oi].map_or(u32::MAX, |b| b + first as u32);
    let grid = [
        [corner[0] as f32, corner[1] as f32, g.u[0] as f32, g.u[1] as f32],
        [g.v[0] as f32, g.v[1] as f32, f32::from_bits(k0 as u32), f32::from_bits(g.nx as u32)],
        [f32::from_bits(v0), 0.0, 0.0, 0.0],
    ];
    TileWork::Lattice { local: l.local, grid }
}

/// The patterns (with their hashes) of lattice tile `t`'s fine, coarse, level (each followed by its
/// group variants, `TileMesh::level_lists`) and occluder draws (`local`: its vertices' (column,
/// row); `remap`, `cidx`: scratch): a run's patterns, as [`Plan::new`] finds them.
#[cfg(test)]
pub(super) fn tile_patterns(
    t: &crate::lod::TileMesh,
    local: &[[u32; 2]],
    remap: &mut Vec<u32>,
    cidx: &mut Vec<u32>,
) -> Vec<(u64, Pattern)> {
    let mut patterns: Vec<(u64, Pattern)> = tile_lists(t).map(|l| list_pattern(t, l, local, remap, cidx)).collect();
    patterns.push(hashed(occluder_pattern(t, local)));
    patterns
}

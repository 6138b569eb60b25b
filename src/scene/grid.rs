//! Reservoir grids (corner-point grids, seed 003) as scene objects: each block of columns is a
//! tile whose LOD levels are the block's cell-merging levels (`crate::grid`), so every culling
//! strategy applies to grid blocks as to horizon tiles, and the renderer picks each block's level
//! by view distance or screen-space error (`render::GridLod`).

use super::{check_color, AddOptions, ObjectKind, Scene};
use crate::camera::MAX_COORD;
use crate::error::{ensure, num, Result};
use crate::grid::{self, CornerGrid, LevelStats};
use crate::lod::levels::MAX_LEVELS;
use glam::DVec3;

/// The most cells per block side: a block's quadtree then has at most [`MAX_LEVELS`] levels
/// above its leaves, the levels every tile can hold.
pub const MAX_BLOCK: usize = 1 << MAX_LEVELS;

/// What a grid object keeps besides its tiles.
#[derive(Clone, Debug, PartialEq)]
pub struct GridInfo {
    /// (nk, nj, ni) cells.
    pub dims: (usize, usize, usize),
    /// (bi, bj) cells per block.
    pub blocks: (usize, usize),
    /// Mean leaf cell size (L along i, W along j) of each block, in tile order.
    pub cell_size: Vec<(f64, f64)>,
    /// Per level 0..: the whole grid's counts (`grid::LevelStats`).
    pub levels: Vec<LevelStats>,
    /// Per block (tile order), per level 0..: its counts; a block with fewer levels stops early.
    pub block_levels: Vec<Vec<LevelStats>>,
}

impl Scene {
    /// Adds a corner-point grid (see `crate::grid::CornerGrid` for the layout): `corners`
    /// (nk, nj, ni, 8, 3) world coordinates, `active` / `region` per cell, `opts.color_by` values
    /// one per cell; `blocks` = (bi, bj) cells per block, each in 1..=`MAX_BLOCK`.
    #[allow(clippy::too_many_arguments)]
    pub fn add_grid(
        &mut self,
        dims: (usize, usize, usize),
        corners: &[f64],
        active: Option<&[bool]>,
        region: Option<&[i32]>,
        blocks: (usize, usize),
        mut opts: AddOptions,
    ) -> Result<u32> {
        let (nk, nj, ni) = dims;
        for (b, name) in [(blocks.0, 0), (blocks.1, 1)] {
            ensure((1..=MAX_BLOCK).contains(&b), "blocks", || {
                format!("blocks[{name}] is {b}; expected 1..={MAX_BLOCK} cells per block")
            })?;
        }
        let n = nk.saturating_mul(nj).saturating_mul(ni);
        ensure(n > 0, "corners", || format!("corners has shape ({nk}, {nj}, {ni}, 8, 3); expected at least one cell"))?;
        let color = check_color(opts.color, self.next_id)?;
        let color_by = super::color_by_arg(&opts.color, opts.color_by.take(), || None)?;
        if let Some(c) = &color_by {
            c.check(Some((n, &format!("one per cell, ({nk}, {nj}, {ni})"))))?;
        }
        let values = color_by.as_ref().and_then(|c| c.values.as_deref());
        let g = CornerGrid { nk, nj, ni, corners, active, region, values };
        // Bounds of the active cells' finite corners (build_grid names a non-finite active corner).
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        if corners.len() == n * 24 {
            for (c, cell) in corners.chunks_exact(24).enumerate() {
                if active.is_some_and(|a| a.get(c) == Some(&false)) {
                    continue;
                }
                for p in cell.chunks_exact(3) {
                    let p = DVec3::new(p[0], p[1], p[2]);
                    if p.is_finite() {
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                }
            }
        }
        if lo.x > hi.x {
            (lo, hi) = (DVec3::ZERO, DVec3::ZERO);
        }
        for (a, v) in lo.to_array().into_iter().chain(hi.to_array()).enumerate() {
            ensure(v.abs() <= MAX_COORD, "corners", || {
                format!("component {}: corners reach {}; coordinates must be within +-{MAX_COORD:e}", a % 3, num(v))
            })?;
        }
        let o = self.origin_for(lo, hi);
        let build = opts.interrupt.run_parallel(|stop| grid::build_grid(&g, o, blocks, stop))??;
        let color_by = color_by.map(|c| c.resolve(super::tile_scalars(&build.tiles, o.z, &c.source))).transpose()?;
        let info = GridInfo {
            dims,
            blocks,
            cell_size: build.cell_size,
            levels: build.levels,
            block_levels: build.block_levels,
        };
        let mut tiles = build.tiles;
        for t in &mut tiles {
            if t.levels.len() > MAX_LEVELS {
                t.levels = t.levels[..MAX_LEVELS].to_vec().into();
            }
        }
        // Cell merging keeps each cell's value (a merged face takes its cells' mean), so grids
        // coloured by values keep their levels: push would drop them for other kinds.
        let id = self.next_id;
        self.push(o, opts.name, ObjectKind::Grid(Box::new(info)), color, None, tiles);
        self.object_mut(id)?.color_by = color_by.map(Box::new);
        Ok(id)
    }

    /// Per object (scene order): whether it is a reservoir grid whose box lies wholly beyond the
    /// near plane (`eye`, unit `forward` and `near` in render space: relative to `origin`, z times
    /// `z_scale`), so the eye is outside all of its cells and the near plane cuts nothing open.
    /// Seen so, the grid's faces without its interior ones (`grid::faces::kind::interior`) bound
    /// its cells, wound outwards: every point of them that the eye sees lies on a face turned
    /// towards it (a ray from outside first meets the cells where it enters them), so a frame
    /// leaves out the interior faces ([`Scene::grid_interior_indices`]) and may cull back faces.
    pub fn seen_from_outside(
        &self,
        origin: DVec3,
        (eye, forward, near): (DVec3, DVec3, f64),
        z_scale: f64,
    ) -> Vec<bool> {
        let zs = DVec3::new(1.0, 1.0, z_scale);
        self.objects()
            .iter()
            .map(|o| {
                if !matches!(o.kind, ObjectKind::Grid(_)) || o.tiles.len() != info_len(&o.kind) {
                    return false;
                }
                let off = o.placement(origin);
                let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
                for t in o.tiles.iter().filter(|t| !t.fine.is_empty()) {
                    lo = lo.min((DVec3::from_array(t.bbox_min.map(f64::from)) + off) * zs);
                    hi = hi.max((DVec3::from_array(t.bbox_max.map(f64::from)) + off) * zs);
                }
                // The box's least depth along the view, beyond the near plane by a margin (f32 positions).
                let m = 1e-5 * (hi - lo).max_element().max(1.0);
                let depth = (0..8)
                    .map(|c| DVec3::select(glam::BVec3::new(c & 1 != 0, c & 2 != 0, c & 4 != 0), hi, lo))
                    .map(|p| (p - eye).dot(forward))
                    .fold(f64::INFINITY, f64::min);
                lo.x <= hi.x && depth > near + m
            })
            .collect()
    }

    /// Per tile (scene tile order): how many indices at the end of the tile's level `level(t)`
    /// a frame leaves out: a grid block's interior triangles (`grid::faces::kind::interior`:
    /// faces between regions and of cavities, ordered last, hidden from any point outside the
    /// grid's cells) when its grid is seen from outside (`outside`, per object:
    /// [`Scene::seen_from_outside`]); 0 for other tiles and views.
    pub fn grid_interior_indices(&self, outside: &[bool], level: impl Fn(usize) -> usize) -> Vec<u32> {
        let mut out = Vec::new();
        for (o, &outside) in self.objects().iter().zip(outside) {
            let (ObjectKind::Grid(info), true) = (&o.kind, o.tiles.len() == info_len(&o.kind)) else {
                out.extend(std::iter::repeat_n(0, o.tiles.len()));
                continue;
            };
            for levels in &info.block_levels {
                let t = out.len();
                let n = match levels.get(level(t).min(levels.len().saturating_sub(1))) {
                    Some(l) if outside => 3 * l.interior_triangles.min(l.triangles),
                    _ => 0,
                };
                out.push(n.min(u32::MAX as u64) as u32);
            }
        }
        out
    }

    /// The grid's per-level counts (`grid::LevelStats`), level 0 first.
    pub fn grid_levels(&self, id: u32) -> Result<&[LevelStats]> {
        match &self.object(id)?.kind {
            ObjectKind::Grid(g) => Ok(&g.levels),
            _ => Err(crate::error::input_err("id", format!("object {id} is not a grid"))),
        }
    }
}

/// A grid's number of blocks (its tile count), 0 for other kinds.
fn info_len(kind: &ObjectKind) -> usize {
    match kind {
        ObjectKind::Grid(g) => g.block_levels.len(),
        _ => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box grid of nk x nj x ni cells 10 m wide, k = 0 at the top.
    fn box_corners(nk: usize, nj: usize, ni: usize) -> Vec<f64> {
        let mut c = Vec::with_capacity(nk * nj * ni * 24);
        for k in 0..nk {
            for j in 0..nj {
                for i in 0..ni {
                    for q in 0..8 {
                        let (di, dj, dk) = (q & 1, (q >> 1) & 1, (q >> 2) & 1);
                        c.extend([((i + di) * 10) as f64, ((j + dj) * 10) as f64, -(((k + dk) * 10) as f64)]);
                    }
                }
            }
        }
        c
    }

    #[test]
    fn a_grid_round_trips_through_bytes_with_its_block_tables() {
        let mut s = Scene::new();
        let id = s.add_grid((2, 4, 4), &box_corners(2, 4, 4), None, None, (2, 2), AddOptions::new(1.0)).unwrap();
        assert_eq!(s.object(id).unwrap().tiles.len(), 4);
        let levels = s.grid_levels(id).unwrap().to_vec();
        assert_eq!(levels[0].faces, 2 * (16 + 8 + 8));
        let t = Scene::from_bytes(&s.to_bytes()).unwrap();
        assert_eq!(t.grid_levels(id).unwrap(), &levels[..]);
        assert_eq!(format!("{:?}", t.object(id).unwrap().kind), format!("{:?}", s.object(id).unwrap().kind));
        let e = s.add_grid((1, 1, 1), &box_corners(1, 1, 1), None, None, (40, 1), AddOptions::new(1.0)).unwrap_err();
        assert!(e.to_string().starts_with("blocks"), "{e}");
        assert!(s.grid_levels(99).is_err());
    }

    /// Interior triangles are left out only while the eye is outside the grid's box.
    #[test]
    fn interior_indices_only_from_outside() {
        let mut s = Scene::new();
        let region: Vec<i32> = (0..2 * 4 * 4).map(|x| (x >= 16) as i32).collect();
        let id =
            s.add_grid((2, 4, 4), &box_corners(2, 4, 4), None, Some(&region), (4, 4), AddOptions::new(1.0)).unwrap();
        let levels = s.grid_levels(id).unwrap().to_vec();
        assert_eq!(levels[0].interior_triangles, 2 * 16 * 2);
        // Render space relative to the world origin: the grid spans (0..40, 0..40, -20..0).
        let at = |p: [f64; 3], f: [f64; 3], near: f64| {
            let outside = s.seen_from_outside(DVec3::ZERO, (DVec3::from_array(p), DVec3::from_array(f), near), 1.0);
            let n = s.grid_interior_indices(&outside, |_| 0);
            assert_eq!(outside, vec![n[0] > 0]);
            n
        };
        let down = [0.0, 0.0, -1.0];
        assert_eq!(at([20.0, 20.0, 50.0], down, 1.0), vec![3 * 64]);
        assert_eq!(at([20.0, 20.0, -10.0], down, 1.0), vec![0]); // inside
        assert_eq!(at([20.0, 20.0, 50.0], down, 60.0), vec![0]); // the near plane cuts the grid open
        assert_eq!(at([-1.0, 20.0, -10.0], [1.0, 0.0, 0.0], 0.1), vec![3 * 64]);
        assert_eq!(at([-1.0, 20.0, -10.0], [0.0, 1.0, 0.0], 0.1), vec![0]); // beside it, not beyond
    }
}

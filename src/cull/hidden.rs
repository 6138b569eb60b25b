//! Occlusion by height fields, proven on the CPU before any GPU work of a conservative frame
//! (three_pass conservative, temporal): tiles that lie wholly under (over) a hole-free stretch of
//! a height field, seen from above (below) through it.
//!
//! The argument runs in the height field's own grid frame ((x, y) in render space is an affine
//! map of the sample indices) over its height blocks (`lod::blocks`: whole fine cells, about 8 a
//! side). A's usable blocks are those without a hole whose tile is drawn this frame at level 0 or
//! at a lattice level (whose error bounds its distance to the fine surface everywhere); over any
//! set of usable blocks that share borders A's surface is continuous (tiles share their border
//! samples at every level) and covers their footprints, with heights, over any plane, within the
//! bounds [`hider::Hider`] gives. Let P be a plane (none, or A's local dip: heights are measured
//! over it, a shear that keeps rays straight, vertical order and convex hulls) and B a convex
//! solid holding what another object draws, given by 8 corners (a box, or a height block's prism
//! along its own plane), wholly under zlo, with the eye above zhi (perspective; orthographic:
//! looking down), and R the index-space rectangle holding, for every corner of B, the points
//! q_hi and q_lo where the ray from the eye through that corner crosses the heights zhi and zlo,
//! with [zlo, zhi] the range of A's blocks that meet R (found by growing R until the range no
//! longer changes), every one of them usable. For any point X of B, its ray's q_hi and q_lo lie in
//! R too (B is convex, its central or parallel projections onto those sheared planes are the hulls
//! of its corners', and the affine map to indices keeps hulls), so the ray between the two heights
//! stays over usable blocks of A: above A's surface at zhi, at or under it at zlo, it crosses the
//! surface in front of X. With R inside A's grid shrunk against the f32 rounding of its vertices,
//! that crossing lies where A's triangles cover every pixel centre, so each fragment of B has a
//! fragment of A in front of it on its pixel; were A hidden there, what hides it hides X too. B
//! has no visible pixel. The same holds upside down. A tile is proven when its box is, or, part by
//! part, its height blocks (prisms along planes fitted to them, in a quadtree from the whole tile
//! down to single blocks) or its sub-boxes.
//!
//! Given up (the tile left to the GPU passes): a tile after [`SOLIDS_PER_TILE`] solids, R
//! meeting an unusable block or leaving the grid,
//! crossings nearer than the near plane (clipped), a gap between B and zlo whose length along the
//! ray is under 1e-4 of the depth (the depth test could let B through), and ranges that keep
//! growing. Holes, tiles outside the frustum and tiles not drawn only make blocks unusable where a
//! ray meets them: stacks of rotated, dipping horizons with undefined rims are proven part by part.

mod flat;
mod hider;

use super::{box_corners, FrameInputs};
use crate::camera::Projection;
use crate::lod::blocks::HeightBlocks;
use glam::{DVec2, DVec3};
use hider::{Hider, Plane};
use rayon::prelude::*;

/// The most solids (box, prisms, sub-boxes) the proof tests of one tile before it gives up on
/// it: a visible tile fails within two or three, a tile hidden under a smooth horizon is proven
/// within a few; curved tiles that would need their every block are left to the GPU passes.
const SOLIDS_PER_TILE: u32 = 16;

/// Per tile: proven hidden by a height field (see the module docs). Only visible tiles with a
/// draw are considered, as hiders and as hidden, and only those where `candidate` holds as hidden
/// (temporal frames skip the tiles seen in the last frame: they are drawn first anyway).
///
/// A height field's tiles are taken as a quadtree over its tile grid ([`Proof::node`]): a block
/// of tiles whose union box is proven hidden is hidden whole (each tile's box lies in it, and the
/// argument holds for every point of a proven solid), one whose union box lies on the eye's side of
/// every hider is left whole to the GPU passes (so does every tile's box in it), and the others
/// are split, down to single tiles, which are tested as before. The blocks change which tests
/// are made, not what is proven sound: a frame's CPU work then follows the blocks that differ,
/// not the number of tiles.
pub fn hidden_by_heightfields(f: &FrameInputs<'_>, candidate: &(dyn Fn(usize) -> bool + Sync)) -> Vec<bool> {
    let g = f.geometry;
    let n = g.n_tiles();
    let drawn = |i: usize| f.object_visible[i] && f.draw_args[i].index_count > 0 && f.draw_args[i].instance_count > 0;
    let hiders = hider::hiders(f, &drawn);
    let mut hidden = vec![false; n];
    if hiders.is_empty() {
        return hidden;
    }
    let want = |b: usize| drawn(b) && candidate(b);
    let proof = Proof { f, hiders: &hiders, want: &want };
    let roots = roots(f);
    let found: Vec<usize> = roots
        .par_iter()
        .flat_map_iter(|r| match r {
            Root::Tile(b) => {
                (want(*b) && proof.tile(*b, &vec![false; hiders.len()])).then_some(*b).into_iter().collect()
            }
            Root::Grid(grid) => proof.node(grid, (0, grid.tx), (0, grid.ty), &vec![false; hiders.len()]),
        })
        .collect();
    for b in found {
        hidden[b] = true;
    }
    hidden
}

/// A height field's tiles on its tile grid: `tiles[iy * tx + ix]`, the frame's tile index.
struct TileGrid {
    tx: usize,
    ty: usize,
    tiles: Vec<Option<usize>>,
}

/// Where the proof starts: a height field's tile grid (a quadtree over it), or a tile of another
/// object alone.
enum Root {
    Grid(TileGrid),
    Tile(usize),
}

/// The frame's roots: every height field with a tile grid as one, every other tile alone.
fn roots(f: &FrameInputs<'_>) -> Vec<Root> {
    let mut out = Vec::new();
    let mut first = 0usize;
    for o in f.scene.objects() {
        let range = first..first + o.tiles.len();
        first = range.end;
        match o.tile_sample_bounds() {
            Some((bx, by)) => {
                let (tx, ty) = (bx.len() - 1, by.len() - 1);
                let mut tiles = vec![None; tx * ty];
                for (t, i) in o.tiles.iter().zip(range) {
                    if let Some(slot) = tiles.get_mut(t.iy as usize * tx + t.ix as usize) {
                        *slot = Some(i);
                    }
                }
                out.push(Root::Grid(TileGrid { tx, ty, tiles }));
            }
            None => out.extend(range.map(Root::Tile)),
        }
    }
    out
}

/// One frame's proof: its inputs, hiders and the tiles it tries to prove hidden.
struct Proof<'a> {
    f: &'a FrameInputs<'a>,
    hiders: &'a [Hider],
    want: &'a (dyn Fn(usize) -> bool + Sync),
}

impl Proof<'_> {
    /// The tiles of `grid`'s block `x0..x1` × `y0..y1` proven hidden (quadtree: see
    /// [`hidden_by_heightfields`]). `hopeless`: per hider, the block lies wholly on the eye's side
    /// of it (found for a block around this one): so does every tile and part in it.
    fn node(
        &self,
        grid: &TileGrid,
        (x0, x1): (usize, usize),
        (y0, y1): (usize, usize),
        hopeless: &[bool],
    ) -> Vec<usize> {
        let members: Vec<usize> = (y0..y1)
            .flat_map(|y| (x0..x1).filter_map(move |x| grid.tiles[y * grid.tx + x]))
            .filter(|&b| (self.want)(b))
            .collect();
        match members.as_slice() {
            [] => return Vec::new(),
            [b] => return if self.tile(*b, hopeless) { vec![*b] } else { Vec::new() },
            _ => {}
        }
        let g = self.f.geometry;
        let (lo, hi) = members
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &b| (lo.min(g.bbox[b].0), hi.max(g.bbox[b].1)));
        let mut hl = hopeless.to_vec();
        let (rlo, rhi, near) = self.f.render_box(members[0], lo, hi);
        let verdict = if near {
            Verdict::Failed
        } else {
            self.solid(g.tile_object_cpu[members[0]], &box_corners(rlo, rhi), false, &mut hl)
        };
        match verdict {
            Verdict::Proven => members,
            Verdict::Hopeless => Vec::new(),
            Verdict::Failed => {
                let (xm, ym) = ((x0 + x1).div_ceil(2), (y0 + y1).div_ceil(2));
                let xs = if x1 - x0 > 1 { vec![(x0, xm), (xm, x1)] } else { vec![(x0, x1)] };
                let ys = if y1 - y0 > 1 { vec![(y0, ym), (ym, y1)] } else { vec![(y0, y1)] };
                let kids: Vec<_> = ys.iter().flat_map(|&y| xs.iter().map(move |&x| (x, y))).collect();
                kids.par_iter().flat_map_iter(|&(x, y)| self.node(grid, x, y, &hl)).collect()
            }
        }
    }

    /// Whether the solid `corners` (render space) of object `object` is hidden by a hider of
    /// another object; `hopeless` marks the hiders a non-dip test finds it on the eye's side of
    /// (skipped, and set here).
    fn solid(&self, object: u32, corners: &[DVec3; 8], dip: bool, hopeless: &mut [bool]) -> Verdict {
        let fc = self.f.fc;
        if corners.iter().any(|&p| (p - fc.eye).dot(fc.forward) <= fc.near * 1.001 + 1e-9) {
            return Verdict::Failed;
        }
        let mut verdict = Verdict::Hopeless;
        for (k, a) in self.hiders.iter().enumerate() {
            if a.object == object || hopeless[k] {
                continue;
            }
            let v = hides(self.f, a, corners, dip);
            if !dip && v == Verdict::Hopeless {
                // The solid on the eye's side of this hider: so is every part of it.
                hopeless[k] = true;
            }
            match v {
                Verdict::Proven => return Verdict::Proven,
                Verdict::Failed => verdict = Verdict::Failed,
                Verdict::Hopeless => {}
            }
        }
        verdict
    }

    /// Whether tile `b` is proven hidden: its box, then its parts, within [`SOLIDS_PER_TILE`]
    /// solids. `hopeless` as [`Self::node`].
    fn tile(&self, b: usize, hopeless: &[bool]) -> bool {
        let (f, g) = (self.f, self.f.geometry);
        let object = g.tile_object_cpu[b];
        let budget = std::cell::Cell::new(SOLIDS_PER_TILE);
        let hopeless = std::cell::RefCell::new(hopeless.to_vec());
        let hidden_solid = |corners: &[DVec3; 8], dip: bool| {
            if budget.get() == 0 {
                return Verdict::Hopeless;
            }
            budget.set(budget.get() - 1);
            self.solid(object, corners, dip, &mut hopeless.borrow_mut())
        };
        // Boxes are tested with heights as they are: a box is level, shearing it makes it taller.
        let hidden_box = |lo: DVec3, hi: DVec3| {
            let (lo, hi, near) = f.render_box(b, lo, hi);
            if near {
                Verdict::Failed
            } else {
                hidden_solid(&box_corners(lo, hi), false)
            }
        };
        match hidden_box(g.bbox[b].0, g.bbox[b].1) {
            Verdict::Proven => true,
            // The tile lies on the eye's side of every hider under it: so does every part of it.
            Verdict::Hopeless => false,
            Verdict::Failed => hidden_in_parts(f, b, &hidden_box, &hidden_solid),
        }
    }
}

/// Whether every part of tile `b` is hidden (`hidden_box`: an origin-relative box,
/// `hidden_solid`: a render-space solid): a height-field tile's height blocks as prisms, grown by
/// the error of the level drawn ([`Parts::hidden`]); another tile's sub-boxes when drawn at
/// level 0.
fn hidden_in_parts(
    f: &FrameInputs<'_>,
    b: usize,
    hidden_box: &dyn Fn(DVec3, DVec3) -> Verdict,
    hidden_solid: &dyn Fn(&[DVec3; 8], bool) -> Verdict,
) -> bool {
    let g = f.geometry;
    if let (Some(hb), Some(e), Some(prism)) = (&g.height_blocks[b], f.exact_level_error(b), Prisms::of(f, b)) {
        let parts = Parts { hb, e, prism, hidden_solid };
        return parts.hidden((0, hb.columns()), (0, hb.rows.len() - 1));
    }
    let parts = &g.sub_boxes[b];
    f.draw_args[b] == g.fine[b]
        && parts.len() > 1
        && parts.iter().all(|&(lo, hi)| hidden_box(lo, hi) == Verdict::Proven)
}

/// A height-field tile's blocks as the proof tests them.
struct Parts<'a> {
    hb: &'a HeightBlocks,
    /// The drawn level's error bound, world units.
    e: f64,
    prism: Prisms,
    hidden_solid: &'a dyn Fn(&[DVec3; 8], bool) -> Verdict,
}

impl Parts<'_> {
    /// Whether blocks `p0..p1` × `q0..q1` are hidden: their prism along their plane (a quadtree
    /// over the blocks: halves or quarters, down to single blocks, the first failing block
    /// ending the test), so that a tile whose surface is nearly planar is proven by one prism.
    fn hidden(&self, (p0, p1): (usize, usize), (q0, q1): (usize, usize)) -> bool {
        let whole = (p0, p1, q0, q1) == (0, self.hb.columns(), 0, self.hb.rows.len() - 1);
        let node = if whole { self.hb.whole } else { self.hb.node_plane((p0, p1), (q0, q1)) };
        let Some((plane, r)) = node else { return true }; // no triangle
        match (self.hidden_solid)(&self.prism.of_node(self.hb, (p0, p1), (q0, q1), plane, r + self.e), true) {
            Verdict::Proven => return true,
            Verdict::Hopeless => return false,
            Verdict::Failed if p1 - p0 == 1 && q1 - q0 == 1 => return false,
            Verdict::Failed => {}
        }
        let (pm, qm) = ((p0 + p1) / 2, (q0 + q1) / 2);
        let ps: &[(usize, usize)] = if p1 - p0 > 1 { &[(p0, pm), (pm, p1)] } else { &[(p0, p1)] };
        let qs: &[(usize, usize)] = if q1 - q0 > 1 { &[(q0, qm), (qm, q1)] } else { &[(q0, q1)] };
        qs.iter().all(|&q| ps.iter().all(|&p| self.hidden(p, q)))
    }
}

/// What makes a height-field tile's block prisms in render space: its grid, its first sample,
/// its object's placement and the frame's exaggeration.
struct Prisms {
    axes: crate::scene::GridAxes,
    first: (usize, usize),
    placement: DVec3,
    z_scale: f64,
}

impl Prisms {
    fn of(f: &FrameInputs<'_>, b: usize) -> Option<Self> {
        let oi = f.geometry.tile_object_cpu[b] as usize;
        let o = &f.scene.objects()[oi];
        let axes = o.grid_axes()?;
        let first_tile = f.geometry.tile_object_cpu.partition_point(|&t| (t as usize) < oi);
        let t = o.tiles.get(b - first_tile)?;
        let (bx, by) = o.tile_sample_bounds()?;
        let first = (*bx.get(t.ix as usize)?, *by.get(t.iy as usize)?);
        Some(Prisms { axes, first, placement: f.placement(oi), z_scale: f.camera.z_scale })
    }

    /// The prism of blocks `p0..p1` × `q0..q1`: their footprint's corners, at `plane`'s heights
    /// (at its corners (p0, q0), (p1, q0), (p0, q1), origin-relative) less and more `r`, in render
    /// space, pushed out against round-off as `render_box` grows boxes. Corner c: bit 0 the larger
    /// column, bit 1 the larger row, bit 2 the top.
    fn of_node(
        &self,
        hb: &HeightBlocks,
        (p0, p1): (usize, usize),
        (q0, q1): (usize, usize),
        plane: [f64; 3],
        r: f64,
    ) -> [DVec3; 8] {
        let [z00, z10, z01] = plane;
        let own = [z00, z10, z01, z10 + z01 - z00];
        let (u, v) = (DVec2::from(self.axes.u).normalize(), DVec2::from(self.axes.v).normalize());
        let zs = self.z_scale;
        let corners: [DVec3; 8] = std::array::from_fn(|c| {
            let (p, q) = (if c & 1 != 0 { p1 } else { p0 }, if c & 2 != 0 { q1 } else { q0 });
            let (i, j) = (self.first.0 + hb.cols[p], self.first.1 + hb.rows[q]);
            let xy = DVec2::from(self.axes.pos(i, j)) + self.placement.truncate();
            let z = own[c & 3] + if c & 4 != 0 { r } else { -r };
            DVec3::new(xy.x, xy.y, (z + self.placement.z) * zs)
        });
        let (lo, hi) = corners.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), &p| (a.min(p), b.max(p)));
        let grow = 1e-6 * lo.abs().max(hi.abs()).max_element() + 1e-4 * (hi - lo).length() + 1e-9;
        std::array::from_fn(|c| {
            let s = |bit: usize| if c & bit != 0 { 1.0 } else { -1.0 };
            let push = (u * s(1) + v * s(2)) * grow;
            corners[c] + DVec3::new(push.x, push.y, s(4) * grow * zs.signum())
        })
    }
}

/// What a test of one solid against the hiders found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Verdict {
    Proven,
    /// Not proven.
    Failed,
    /// Not proven, and no part of the solid would be: it lies wholly on the eye's side of every
    /// hider's blocks under it (or no hider has a usable block there), or the tile's budget of
    /// solids is spent. Only a shortcut: the tile is then left to the GPU passes.
    Hopeless,
}

/// The index-space bounds of render-space points `ps`.
fn index_bounds(a: &Hider, ps: impl Iterator<Item = DVec2>) -> (DVec2, DVec2) {
    ps.map(|p| a.index(p)).fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), q| (lo.min(q), hi.max(q)))
}

/// Whether height field `a` hides every point of the convex hull of `corners` (render space;
/// the module docs' argument): with heights as they are, or (`dip`, where `a` has one there) as
/// heights over `a`'s local dip around it.
fn hides(f: &FrameInputs<'_>, a: &Hider, corners: &[DVec3; 8], dip: bool) -> Verdict {
    let m = a.margin();
    let (lo, hi) = index_bounds(a, corners.iter().map(|p| p.truncate()));
    // Quick rejection by the tiles' ranges, which hold the blocks' (heights as they are).
    let Some((zlo, zhi)) = a.coarse(lo, hi) else { return Verdict::Hopeless };
    let (bz_lo, bz_hi) = corners.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |r, p| (r.0.min(p.z), r.1.max(p.z)));
    let (fc, persp) = (f.fc, f.fc.projection == Projection::Perspective);
    let above = if persp { fc.eye.z > zhi } else { fc.forward.z < 0.0 };
    let below = if persp { fc.eye.z < zlo } else { fc.forward.z > 0.0 };
    if !dip && ((above && bz_lo > zhi) || (below && bz_hi < zlo)) {
        return Verdict::Hopeless;
    }
    match a.dip(lo, hi).filter(|_| dip) {
        Some(plane) => hides_over(f, a, corners, (lo, hi), m, &plane),
        None => hides_over(f, a, corners, (lo, hi), m, &Plane::FLAT),
    }
}

/// The module docs' argument with heights over `plane`: `corners` those of B, `lo..hi` its
/// footprint in `a`'s index space, `m` the margin in samples.
fn hides_over(
    f: &FrameInputs<'_>,
    a: &Hider,
    corners: &[DVec3; 8],
    (lo, hi): (DVec2, DVec2),
    m: f64,
    plane: &Plane,
) -> Verdict {
    let fc = f.fc;
    let persp = fc.projection == Projection::Perspective;
    let (bz_lo, bz_hi) = corners
        .iter()
        .map(|&p| plane.over(p))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |r, z| (r.0.min(z), r.1.max(z)));
    let (eye, forward) = (plane.over(fc.eye), plane.slope(fc.forward));
    // Start from the blocks under B's own footprint, then grow.
    // No usable block under B: hopeless (so is any solid over part of that footprint); more
    // blocks than one query reads: only failed (a smaller solid may be proven).
    let Some(mut z) = a.first_guess(lo, hi, plane) else {
        return if a.too_many(lo, hi, plane) { Verdict::Failed } else { Verdict::Hopeless };
    };
    let (above, below) = (if persp { eye > z.1 } else { forward < 0.0 }, if persp { eye < z.0 } else { forward > 0.0 });
    if (above && bz_lo > z.1) || (below && bz_hi < z.0) {
        return Verdict::Hopeless; // B lies wholly on the eye's side of A's blocks under it
    }
    for _ in 0..6 {
        let (zlo, zhi) = z;
        let down = bz_hi < zlo && if persp { eye > zhi } else { forward < 0.0 };
        let up = bz_lo > zhi && if persp { eye < zlo } else { forward > 0.0 };
        if !(down || up) {
            return Verdict::Failed;
        }
        let gap = if down { zlo - bz_hi } else { bz_lo - zhi };
        let mut crossings = Vec::with_capacity(16);
        for &p in corners {
            let d = if persp { p - fc.eye } else { fc.forward };
            let dz = plane.slope(d);
            // The ray's length over the gap, against the point's depth, must stay far above the
            // depth buffer's precision.
            if dz == 0.0 || gap * d.length() / dz.abs() <= 1e-4 * (p - fc.eye).dot(fc.forward).abs() {
                return Verdict::Failed;
            }
            for h in [zlo, zhi] {
                let q = p + d * ((h - plane.over(p)) / dz);
                if (q - fc.eye).dot(fc.forward) <= fc.near * 1.001 + 1e-9 {
                    return Verdict::Failed;
                }
                crossings.push(q.truncate());
            }
        }
        let (lo, hi) = index_bounds(a, crossings.into_iter());
        let Some(met) = a.range(lo, hi, m, plane) else { return Verdict::Failed };
        if met.0 >= zlo && met.1 <= zhi {
            return Verdict::Proven; // the blocks R meets lie within the range R was made from
        }
        z = (met.0.min(zlo), met.1.max(zhi));
    }
    Verdict::Failed
}

/// `f`'s per-tile visibility with the tiles proven hidden switched off (so that no pass draws,
/// counts or tests them), and how many there are; `candidate` as [`hidden_by_heightfields`].
pub fn visible_without_hidden(f: &FrameInputs<'_>, candidate: &(dyn Fn(usize) -> bool + Sync)) -> (Vec<bool>, u64) {
    let hidden = hidden_by_heightfields(f, candidate);
    let mask: Vec<bool> = f.object_visible.iter().zip(&hidden).map(|(&v, &h)| v && !h).collect();
    (mask, hidden.iter().filter(|&&h| h).count() as u64)
}

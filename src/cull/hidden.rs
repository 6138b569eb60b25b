//! Occlusion by height fields, proven on the CPU before any GPU work of a conservative frame
//! (three_pass conservative, temporal): tiles that lie wholly under (over) a hole-free stretch of
//! a height field, seen from above (below) through it.
//!
//! The argument runs in the height field's own grid frame: (x, y) in render space is an affine
//! map of the sample indices (column, row), z is z. Let A be a height field and its usable tiles
//! those drawn this frame and hole-free (all cells of the tile defined): over any set of usable
//! tiles that share borders, A's surface, at any level of detail, is continuous (tiles share their
//! border samples at full resolution) and covers their footprints, with heights within their
//! boxes' [zlo, zhi]. Let B be another object's tile, wholly under zlo, with the eye above zhi
//! (perspective; orthographic: looking down), and R the index-space rectangle holding, for every
//! corner of B's box, the points q_hi and q_lo where the ray from the eye through that corner
//! crosses the heights zhi and zlo, with [zlo, zhi] the range of A's tiles that meet R (found by
//! growing R until the range no longer changes), every one of them usable. For any point P of
//! B's box, its ray's q_hi and q_lo lie in R too (the box is convex, its central or parallel
//! projections onto those planes are the hulls of its corners', and the affine map to indices
//! keeps hulls), so the ray between the two heights stays over usable tiles of A: above A's
//! surface at zhi, at or under it at zlo, it crosses the surface at a point X in front of P. With
//! R inside A's grid shrunk against the f32 rounding of its vertices, X lies where A's triangles
//! cover every pixel centre, so each fragment of B has a fragment of A in front of it on its
//! pixel; were A hidden at X, what hides it hides P too. B has no visible pixel. The same holds
//! upside down. Holes, tiles outside the frustum and other tiles not drawn only make R's tiles
//! unusable where a ray meets them: stacks of rotated horizons with undefined rims are proven
//! tile by tile. Given up (the tile left to the GPU passes): R meeting an unusable tile or leaving
//! the grid, crossings nearer than the near plane (clipped), a gap between B and zlo under 1e-4
//! of the depth (the depth test could let B through), and ranges that keep growing.

use super::{box_corners, FrameInputs};
use crate::camera::Projection;
use crate::lod::tile_bounds;
use glam::{DMat2, DVec2, DVec3};

/// A height field drawn this frame: its tiles on their grid, in index space.
struct Hider {
    object: u32,
    /// Render-space (x, y) -> (column, row) of the grid: `inv * (xy - at0)`.
    at0: DVec2,
    inv: DMat2,
    /// Tile column and row boundaries in samples: tile (ix, iy) spans columns xb[ix]..xb[ix + 1]
    /// and rows yb[iy]..yb[iy + 1].
    xb: Vec<f64>,
    yb: Vec<f64>,
    /// Per tile (row-major by iy, then ix) its render-space z range; None = not usable (holes,
    /// not drawn this frame, empty).
    z: Vec<Option<(f64, f64)>>,
}

impl Hider {
    /// Column and row of render-space (x, y).
    fn index(&self, p: DVec2) -> DVec2 {
        self.inv * (p - self.at0)
    }

    /// The z range of the tiles meeting index rectangle `lo..hi`, or None when it leaves the
    /// grid shrunk by `m` samples or meets a tile that is not usable.
    fn range(&self, lo: DVec2, hi: DVec2, m: f64) -> Option<(f64, f64)> {
        let (xb, yb) = (&self.xb, &self.yb);
        let (tx, ty) = (xb.len() - 1, yb.len() - 1);
        if !(lo.x >= xb[0] + m && hi.x <= xb[tx] - m && lo.y >= yb[0] + m && hi.y <= yb[ty] - m) {
            return None;
        }
        self.tiles_meeting(lo, hi).try_fold((f64::INFINITY, f64::NEG_INFINITY), |r, z| {
            let (a, b) = z?;
            Some((r.0.min(a), r.1.max(b)))
        })
    }

    /// The z range of the usable tiles meeting `lo..hi` (clamped to the grid), None without any:
    /// where the proof starts from, not what it rests on.
    fn first_guess(&self, lo: DVec2, hi: DVec2) -> Option<(f64, f64)> {
        let r = self
            .tiles_meeting(lo, hi)
            .flatten()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |r, (a, b)| (r.0.min(a), r.1.max(b)));
        (r.0 <= r.1).then_some(r)
    }

    /// The tiles meeting index rectangle `lo..hi`, the grid's border tiles for parts beyond it.
    fn tiles_meeting(&self, lo: DVec2, hi: DVec2) -> impl Iterator<Item = Option<(f64, f64)>> + '_ {
        let (xb, yb) = (&self.xb, &self.yb);
        let (tx, ty) = (xb.len() - 1, yb.len() - 1);
        let i0 = xb[1..tx].partition_point(|&b| b < lo.x);
        let i1 = xb[1..tx].partition_point(|&b| b <= hi.x);
        let j0 = yb[1..ty].partition_point(|&b| b < lo.y);
        let j1 = yb[1..ty].partition_point(|&b| b <= hi.y);
        (j0..=j1).flat_map(move |j| self.z[j * tx + i0..=j * tx + i1].iter().copied())
    }
}

/// Per tile: proven hidden by a height field (see the module docs). Only visible tiles with a
/// draw are considered, as hiders and as hidden.
pub fn hidden_by_heightfields(f: &FrameInputs<'_>) -> Vec<bool> {
    let g = f.geometry;
    let n = g.n_tiles();
    let drawn = |i: usize| f.object_visible[i] && f.draw_args[i].index_count > 0 && f.draw_args[i].instance_count > 0;
    let hiders = hiders(f, &drawn);
    let mut hidden = vec![false; n];
    if hiders.is_empty() {
        return hidden;
    }
    for (b, h) in hidden.iter_mut().enumerate().filter(|(b, _)| drawn(*b)) {
        let (lo, hi, near) = f.render_box(b, g.bbox[b].0, g.bbox[b].1);
        *h = !near && hiders.iter().any(|a| a.object != g.tile_object_cpu[b] && hides(f, a, (lo, hi)));
    }
    hidden
}

fn hiders(f: &FrameInputs<'_>, drawn: &dyn Fn(usize) -> bool) -> Vec<Hider> {
    let g = f.geometry;
    let mut first = 0usize;
    let mut out = Vec::new();
    for (oi, o) in f.scene.objects().iter().enumerate() {
        let range = first..first + o.tiles.len();
        first = range.end;
        let Some(axes) = o.grid_axes() else { continue };
        let tx = o.tiles.iter().map(|t| t.ix).max().unwrap_or(0) as usize + 1;
        let ty = o.tiles.iter().map(|t| t.iy).max().unwrap_or(0) as usize + 1;
        let m = DMat2::from_cols(DVec2::from(axes.u), DVec2::from(axes.v));
        if range.is_empty() || tx * ty != o.tiles.len() || axes.nx < 2 || axes.ny < 2 || m.determinant() == 0.0 {
            continue;
        }
        let (bx, by) = (tile_bounds(axes.nx, tx), tile_bounds(axes.ny, ty));
        let mut z = vec![None; tx * ty];
        let mut any = false;
        for (t, i) in o.tiles.iter().zip(range) {
            let (ix, iy) = (t.ix as usize, t.iy as usize);
            let cells = (bx[ix + 1] - bx[ix]) * (by[iy + 1] - by[iy]);
            if drawn(i) && g.occluder[i].index_count > 0 && cells > 0 && t.fine_triangles() == 2 * cells {
                let (lo, hi) = f.render_space_box(i, g.bbox[i].0, g.bbox[i].1);
                z[iy * tx + ix] = Some((lo.z, hi.z));
                any = true;
            }
        }
        let sorted = |b: &[usize]| b.windows(2).all(|w| w[0] < w[1]);
        if any && sorted(&bx) && sorted(&by) {
            let at0 = DVec2::from(axes.o) + f.placement(oi).truncate();
            let as_f64 = |b: Vec<usize>| b.into_iter().map(|v| v as f64).collect();
            out.push(Hider { object: oi as u32, at0, inv: m.inverse(), xb: as_f64(bx), yb: as_f64(by), z });
        }
    }
    out
}

/// The index-space bounds of render-space points `ps`.
fn index_bounds(a: &Hider, ps: impl Iterator<Item = DVec2>) -> (DVec2, DVec2) {
    ps.map(|p| a.index(p)).fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), q| (lo.min(q), hi.max(q)))
}

/// Whether height field `a` hides every point of box `blo..bhi` (the module docs' argument).
fn hides(f: &FrameInputs<'_>, a: &Hider, (blo, bhi): (DVec3, DVec3)) -> bool {
    let fc = f.fc;
    let persp = fc.projection == Projection::Perspective;
    // Against the f32 rounding of A's vertices: a margin in world units, then in samples (the
    // inverse map stretches no length by more than its Frobenius norm).
    let diagonal = a.inv.inverse() * DVec2::new(a.xb[a.xb.len() - 1], a.yb[a.yb.len() - 1]);
    let world = 1e-4 * diagonal.length() + 1e-6 * a.at0.abs().max_element().max(diagonal.abs().max_element());
    let m = world * (a.inv.x_axis.length_squared() + a.inv.y_axis.length_squared()).sqrt();
    let corners = box_corners(blo, bhi);
    // Start from the tiles under B's own footprint, then grow.
    let (lo, hi) = index_bounds(a, corners[..4].iter().map(|p| p.truncate()));
    let Some(mut z) = a.first_guess(lo, hi) else { return false };
    for _ in 0..6 {
        let (zlo, zhi) = z;
        let down = bhi.z < zlo && if persp { fc.eye.z > zhi } else { fc.forward.z < 0.0 };
        let up = blo.z > zhi && if persp { fc.eye.z < zlo } else { fc.forward.z > 0.0 };
        if !(down || up) {
            return false;
        }
        let gap = if down { zlo - bhi.z } else { blo.z - zhi };
        let mut crossings = Vec::with_capacity(16);
        for &p in &corners {
            let d = if persp { p - fc.eye } else { fc.forward };
            // The ray's length over the gap, against the point's depth, must stay far above the
            // depth buffer's precision.
            if d.z == 0.0 || gap * d.length() / d.z.abs() <= 1e-4 * (p - fc.eye).dot(fc.forward).abs() {
                return false;
            }
            for h in [zlo, zhi] {
                let q = p + d * ((h - p.z) / d.z);
                if (q - fc.eye).dot(fc.forward) <= fc.near * 1.001 + 1e-9 {
                    return false;
                }
                crossings.push(q.truncate());
            }
        }
        let (lo, hi) = index_bounds(a, crossings.into_iter());
        let Some(met) = a.range(lo, hi, m) else { return false };
        if met.0 >= zlo && met.1 <= zhi {
            return true; // the tiles R meets lie within the range R was made from
        }
        z = (met.0.min(zlo), met.1.max(zhi));
    }
    false
}

/// `f`'s per-tile visibility with the tiles proven hidden switched off (so that no pass draws,
/// counts or tests them), and how many there are.
pub fn visible_without_hidden(f: &FrameInputs<'_>) -> (Vec<bool>, u64) {
    let hidden = hidden_by_heightfields(f);
    let mask: Vec<bool> = f.object_visible.iter().zip(&hidden).map(|(&v, &h)| v && !h).collect();
    (mask, hidden.iter().filter(|&&h| h).count() as u64)
}

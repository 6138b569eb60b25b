//! Occlusion by height fields, proven on the CPU before any GPU work of a conservative frame
//! (three_pass conservative, temporal): tiles that lie wholly under (over) a hole-free stretch of
//! a height field, seen from above (below) through it.
//!
//! Let A be an unrotated height field whose tiles are all drawn and hole-free: its surface, at
//! any level of detail, is continuous over its rectangle (tiles share their border samples), and
//! over any set of its tiles its heights lie within their boxes' [zlo, zhi]. Let B be another
//! tile, wholly under zlo, with the eye above zhi (perspective; orthographic: looking down), and
//! R the rectangle holding, for every corner of B's box, the points q_hi and q_lo where the ray
//! from the eye through that corner crosses the heights zhi and zlo, with [zlo, zhi] the range of
//! A's tiles that meet R (found by growing R until the range no longer changes). For any point P
//! of B's box, its ray's q_hi and q_lo lie in R too (the box is convex, and its central or parallel
//! projections onto those planes are the hulls of its corners'), so the ray between the two
//! heights stays over A's tiles that meet R: above A's surface at zhi, at or under it at zlo, it
//! crosses the surface at a point X in front of P. With R inside A's rectangle (shrunk against
//! the f32 rounding of its vertices), X lies where A's triangles cover every pixel centre, so each
//! fragment of B has a fragment of A in front of it on its pixel; were A hidden at X, what hides
//! it hides P too. B has no visible pixel. The same holds upside down. Given up (the tile left to
//! the GPU passes): crossings nearer than the near plane (clipped), a gap between B and zlo under
//! 1e-4 of the depth (the depth test could let B through), rotated height fields (their tiles'
//! boxes are not their footprints), height fields with holes or hidden tiles, and ranges that
//! keep growing.

use super::{box_corners, FrameInputs};
use crate::camera::Projection;
use glam::{DVec2, DVec3};

/// An unrotated, hole-free, wholly drawn height field: its tiles on their grid.
struct Hider {
    object: u32,
    /// Tile column and row boundaries (render space): tile (ix, iy) spans xb[ix]..xb[ix + 1],
    /// yb[iy]..yb[iy + 1].
    xb: Vec<f64>,
    yb: Vec<f64>,
    /// Per tile (row-major by iy, then ix) its render-space z range.
    z: Vec<(f64, f64)>,
}

impl Hider {
    /// The z range of the tiles meeting rectangle `lo..hi`, or None when it leaves the height
    /// field's rectangle shrunk by `m`.
    fn range(&self, lo: DVec2, hi: DVec2, m: f64) -> Option<(f64, f64)> {
        let (xb, yb) = (&self.xb, &self.yb);
        let (tx, ty) = (xb.len() - 1, yb.len() - 1);
        if lo.x < xb[0] + m || hi.x > xb[tx] - m || lo.y < yb[0] + m || hi.y > yb[ty] - m {
            return None;
        }
        let i0 = xb[1..tx].partition_point(|&b| b < lo.x);
        let i1 = xb[1..tx].partition_point(|&b| b <= hi.x);
        let j0 = yb[1..ty].partition_point(|&b| b < lo.y);
        let j1 = yb[1..ty].partition_point(|&b| b <= hi.y);
        let mut r = (f64::INFINITY, f64::NEG_INFINITY);
        for j in j0..=j1 {
            for &(a, b) in &self.z[j * tx + i0..=j * tx + i1] {
                r = (r.0.min(a), r.1.max(b));
            }
        }
        Some(r)
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
    let objects = f.scene.objects();
    let mut first = 0usize;
    let mut out = Vec::new();
    for (oi, o) in objects.iter().enumerate() {
        let range = first..first + o.tiles.len();
        first = range.end;
        let unrotated = o.grid_axes().is_some_and(|a| a.u[1] == 0.0 && a.v[0] == 0.0);
        if !unrotated || range.is_empty() || !range.clone().all(|i| drawn(i) && g.occluder[i].index_count > 0) {
            continue;
        }
        let tx = o.tiles.iter().map(|t| t.ix).max().unwrap_or(0) as usize + 1;
        let ty = o.tiles.iter().map(|t| t.iy).max().unwrap_or(0) as usize + 1;
        if tx * ty != o.tiles.len() {
            continue;
        }
        let (mut xb, mut yb) = (vec![f64::NAN; tx + 1], vec![f64::NAN; ty + 1]);
        let mut z = vec![(0.0, 0.0); tx * ty];
        for (t, i) in o.tiles.iter().zip(range) {
            let (lo, hi) = f.render_space_box(i, g.bbox[i].0, g.bbox[i].1);
            let (ix, iy) = (t.ix as usize, t.iy as usize);
            (xb[ix], xb[ix + 1], yb[iy], yb[iy + 1]) = (lo.x, hi.x, lo.y, hi.y);
            z[iy * tx + ix] = (lo.z, hi.z);
        }
        let sorted = |b: &[f64]| b.windows(2).all(|w| w[0] < w[1]);
        if sorted(&xb) && sorted(&yb) {
            out.push(Hider { object: oi as u32, xb, yb, z });
        }
    }
    out
}

/// Whether height field `a` hides every point of box `blo..bhi` (the module docs' argument).
fn hides(f: &FrameInputs<'_>, a: &Hider, (blo, bhi): (DVec3, DVec3)) -> bool {
    let fc = f.fc;
    let persp = fc.projection == Projection::Perspective;
    let extent = DVec2::new(a.xb[a.xb.len() - 1] - a.xb[0], a.yb[a.yb.len() - 1] - a.yb[0]);
    let m = 1e-4 * extent.length() + 1e-6 * a.xb[0].abs().max(a.yb[0].abs()).max(extent.max_element());
    let corners = box_corners(blo, bhi);
    // Start from the tiles under B's own footprint, then grow.
    let Some(mut z) = a.range(blo.truncate(), bhi.truncate(), m) else { return false };
    for _ in 0..6 {
        let (zlo, zhi) = z;
        let down = bhi.z < zlo && if persp { fc.eye.z > zhi } else { fc.forward.z < 0.0 };
        let up = blo.z > zhi && if persp { fc.eye.z < zlo } else { fc.forward.z > 0.0 };
        if !(down || up) {
            return false;
        }
        let gap = if down { zlo - bhi.z } else { blo.z - zhi };
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
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
                (lo, hi) = (lo.min(q.truncate()), hi.max(q.truncate()));
            }
        }
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

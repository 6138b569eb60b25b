//! Slabs: a closed shell that holds a height-field tile's surface and follows it, the occludee
//! the conservative box test rasterises in place of the tile's boxes (`crate::cull::phases`).
//!
//! Contract of [`heightfield_slab`]: the tile is cut, by halving from the whole tile (whole fine
//! cells each), into pieces, each closed by a prism of its own:
//! * a piece whose samples are all finite and whose error is at most [`TOLERANCE`] sample
//!   spacings (or that is one fine cell, whose error is 0) is bounded by its coarse surface (two
//!   triangles over its corner samples, split as the fine cells are) moved up and down by its
//!   error: the largest vertical distance between that surface and the fine triangles, found at
//!   the fine samples and where the coarse diagonal crosses a fine edge (both surfaces are
//!   piecewise linear, so the distance is largest at a vertex of their overlay). The prism's top
//!   over the piece is then at or above, its bottom at or below, every fine point there;
//! * a piece with no finite sample is left out;
//! * any other piece is halved, down to one fine cell with a hole at a corner, which gets a
//!   prism over each of its fine triangles whose corners are finite (the triangle, thickened).
//!
//! So a smooth tile is one prism (12 triangles), the slab follows a survey's ragged outline to
//! the fine cell, nothing of it stands where the surface has no data, and it stays thin across
//! faults and folds, where the pieces are small.
//!
//! The slab's gate ([`Slab::gate`]) is built the same way at [`GATE_TOLERANCE`], except that a
//! piece with holes whose samples are at least half finite and whose finite heights span little
//! stands as one flat prism over its whole area from the lowest to the highest of them (a fine
//! triangle lies over its piece, between its corners' heights). It holds every fine triangle
//! too, in a few dozen triangles where a tile with a ragged outline has hundreds; the box test
//! draws a slab only where its gate counts a pixel.
//!
//! Every fine triangle lies in the slab; a ray that meets the tile's surface therefore enters the
//! slab at or in front of it, which is what the box test's argument needs of an occludee
//! (`crate::cull::phases`). Unlike the tile's box (as tall as the tile's whole height range: 70 m
//! and more on a dipping horizon, taller than the gap to the next horizon) the slab is as thick
//! as the surface departs from its coarse lattice, a metre or two on a smooth horizon. Rotated
//! grids need nothing more: positions come from the grid.
//!
//! Round-off: vertices on the tile's outline are pushed out across it (along the grid's axes) by
//! `1e-4` of the tile's diagonal, a lone triangle's corners away from its centroid by as much,
//! and every bound is thickened by three times the steepest slope between neighbouring samples
//! times that push (what the push can tilt a surface by), so that no wall or face falls inside the
//! surface it bounds; f32 heights are rounded outwards.

use glam::DVec2;

/// A piece whose coarse surface departs from the fine one by more than this many sample spacings
/// is halved (down to single fine cells, which are exact).
pub const TOLERANCE: f64 = 0.25;

/// [`TOLERANCE`] of a slab's gate ([`Slab::gate`]); a gate's piece with holes stands when its
/// finite heights span at most twice this many sample spacings (and half its samples are
/// finite). On the Reek field's 8 views (commit log) 0.5 and 1 gave the same box-test time, 2
/// and 4 more: the gates' own triangles against the slabs they let through.
pub const GATE_TOLERANCE: f64 = 1.0;

/// A vertex of a shell's prism as the box test draws it (slab_test.wgsl): its origin-relative
/// position, then `out` as snorm8: its corner's miter across the prism's walls (x, y: the vector
/// that moves both walls at the corner out by 1, over 4), the steepest slope of its prism's top
/// and bottom over 8, rounded up (z), and its side (+127 on top surfaces, -127 on bottom ones).
/// The test grows each prism by a fraction of a pixel along the miters and z (box_test.wgsl
/// `grown`), so that the snapping of vertices to the rasteriser's sub-pixel grid cannot uncover a
/// pixel the fine surface covers where a prism's wall stands on the surface's edge (a hole's, or
/// the tile's outline).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShellVertex {
    pub pos: [f32; 3],
    pub out: [i8; 4],
}

impl ShellVertex {
    /// +1 on a top surface, -1 on a bottom one.
    pub fn side(&self) -> f32 {
        f32::from(self.out[3].signum())
    }
}

/// Closed prisms: vertices ([`ShellVertex`]) and triangles over them, each prism's faces wound
/// outwards (as [`Slab`]'s).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shell {
    pub vertices: Vec<ShellVertex>,
    pub indices: Vec<u32>,
}

/// A tile's slab (see the module's contract) as the box test draws it: vertices
/// ([`ShellVertex`]) and triangles over them, each prism's faces wound outwards
/// (counter-clockwise seen from outside), so that the test counts front faces only: the ray's
/// entry into the solid, one per pixel per prism, as a box's.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Slab {
    pub vertices: Vec<ShellVertex>,
    pub indices: Vec<u32>,
    /// A coarser slab of the same tile ([`GATE_TOLERANCE`]; pieces with holes bounded by a flat
    /// prism over their finite heights): it too holds every fine triangle, in a few dozen
    /// triangles where the slab has hundreds. The box test draws it first, as the gate of the
    /// slab (`crate::cull::phases`); empty where it would not be smaller than the slab.
    pub gate: Shell,
    /// Whether the errors of the tile's levels of detail bound their vertical distance to the
    /// fine surface everywhere: lattice levels (`super::levels::lattice_levels`), or a tile with
    /// holes whose simplified levels were measured over its fine triangles
    /// (`super::levels::grid_level_error`). Then the slab grown by a level's error holds that
    /// level. Set by the tile's builder.
    pub levels_exact: bool,
    /// The tile's height blocks (`super::blocks`), built with the slab from the same samples:
    /// what the CPU proof of hidden tiles reads and the tile's sub-boxes are made of.
    pub blocks: std::sync::Arc<super::blocks::HeightBlocks>,
}

/// A height field's slabs, one per tile (None: the tile gets none and is box-tested), built at
/// most once: with its tiles (`super::tile_heightfield`), or for tiles read from bytes when a
/// renderer first needs them (`Object::slabs`), so that loading a scene allocates no slabs. Clones
/// keep what is built.
#[derive(Clone, Default)]
pub struct TileSlabs(std::sync::OnceLock<Vec<Option<Slab>>>);

impl TileSlabs {
    /// Slabs already built.
    pub fn built(slabs: Vec<Option<Slab>>) -> Self {
        Self(std::sync::OnceLock::from(slabs))
    }
    /// The slabs, if built.
    pub fn get(&self) -> Option<&[Option<Slab>]> {
        self.0.get().map(Vec::as_slice)
    }
    /// The slabs, built by `build` on the first call (concurrent first calls build once).
    pub fn get_or_build(&self, build: impl FnOnce() -> Vec<Option<Slab>>) -> &[Option<Slab>] {
        self.0.get_or_init(build)
    }
}

/// Opaque: slabs are derived from the tiles, so whether they are built yet does not show (an
/// object read back from bytes formats as the one written).
impl std::fmt::Debug for TileSlabs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("TileSlabs(..)")
    }
}

/// What [`Sampled::census`] finds of a piece's samples.
struct Census {
    fill: Fill,
    lo: f64,
    hi: f64,
    finite: usize,
    samples: usize,
}

/// A cell's samples: all finite, none, or some.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Fill {
    Full,
    Empty,
    Partial,
}

/// The slab of a height-field tile of `w` × `h` samples (see the module's contract): `pos(li, lj)`
/// the origin-relative (x, y) of local sample (li, lj), `z(li, lj)` its origin-relative height
/// (NaN: a hole). None when the tile has no finite sample or fewer than 2 samples a side.
pub fn heightfield_slab(
    w: usize,
    h: usize,
    pos: impl Fn(usize, usize) -> (f64, f64),
    z: impl Fn(usize, usize) -> f64,
) -> Option<Slab> {
    if w < 2 || h < 2 {
        return None;
    }
    let (p00, p11) = (pos(0, 0), pos(w - 1, h - 1));
    let (pa, pb) = (pos(w - 1, 0), pos(0, h - 1));
    let diag = (DVec2::new(p11.0 - p00.0, p11.1 - p00.1).length()).max(DVec2::new(pb.0 - pa.0, pb.1 - pa.1).length());
    // The steepest slope between neighbouring samples: the surface rises by at most twice that
    // per unit of horizontal distance in any direction, so pushing the outline out by `push`
    // moves the top and bottom surfaces by at most `thick`, by which every vertex is thickened.
    let push = 1e-4 * diag;
    let mut slope = 0.0f64;
    for lj in 0..h {
        for li in 0..w {
            for (di, dj) in [(1, 0), (0, 1)] {
                let (i, j) = (li + di, lj + dj);
                if i < w && j < h {
                    let (a, b) = (z(li, lj), z(i, j));
                    let (p, q) = (pos(li, lj), pos(i, j));
                    let d = DVec2::new(q.0 - p.0, q.1 - p.1).length();
                    if a.is_finite() && b.is_finite() && d > 0.0 {
                        slope = slope.max((b - a).abs() / d);
                    }
                }
            }
        }
    }
    let thick = 3.0 * slope * push;
    // Cells whose coarse surface departs from the fine one by more than this are refined
    // ([`TOLERANCE`] of the mean sample spacing): a fault's step or a sharp fold gets small cells.
    let spacing = (DVec2::from(pos(w - 1, 0)) - DVec2::from(p00)).length() / (w - 1) as f64;
    let spacing = 0.5 * (spacing + (DVec2::from(pos(0, h - 1)) - DVec2::from(p00)).length() / (h - 1) as f64);
    // The grid's axes, and (x, y) of a sample pushed out across the tile's outline (along the
    // axes, so that no sample leaves the cells about it).
    let axis = |q: (f64, f64)| DVec2::new(q.0 - p00.0, q.1 - p00.1).normalize_or_zero();
    let (ai, aj) = (axis(pos(1, 0)), axis(pos(0, 1)));
    // A grid whose rows run clockwise from its columns (yflip) turns every winding over.
    let flip = ai.perp_dot(aj) < 0.0;
    let xy = |li: usize, lj: usize| -> [f32; 2] {
        let (x, y) = pos(li, lj);
        let mut p = DVec2::new(x, y);
        let side = |at_lo: bool, at_hi: bool| {
            if at_lo {
                -1.0
            } else if at_hi {
                1.0
            } else {
                0.0
            }
        };
        p += (ai * side(li == 0, li == w - 1) + aj * side(lj == 0, lj == h - 1)) * push;
        [p.x as f32, p.y as f32]
    };
    let at = Sampled { pos: &pos, z: &z, xy: &xy, thick, push, flip };
    let fine = at.shell((w, h), TOLERANCE * spacing, false);
    if fine.indices.is_empty() {
        return None;
    }
    let gate = at.shell((w, h), GATE_TOLERANCE * spacing, true);
    // A gate no smaller than the slab would only add a pass's work.
    let gate = if gate.indices.len() < fine.indices.len() { gate } else { Shell::default() };
    Some(Slab { vertices: fine.vertices, indices: fine.indices, gate, ..Slab::default() })
}

/// What [`heightfield_slab`] builds its shells from: the tile's samples (`pos`, `z`), their
/// (x, y) pushed out across the outline (`xy`), the thickening against round-off, the push, and
/// whether windings turn over.
struct Sampled<'a, P, Z, X> {
    pos: &'a P,
    z: &'a Z,
    xy: &'a X,
    thick: f64,
    push: f64,
    flip: bool,
}

impl<P, Z, X> Sampled<'_, P, Z, X>
where
    P: Fn(usize, usize) -> (f64, f64),
    Z: Fn(usize, usize) -> f64,
    X: Fn(usize, usize) -> [f32; 2],
{
    /// The samples of `a..=b`, in one pass: whether all, none or some are finite, and the lowest
    /// and highest finite height.
    fn census(&self, a: (usize, usize), b: (usize, usize)) -> Census {
        let (mut lo, mut hi, mut finite) = (f64::INFINITY, f64::NEG_INFINITY, 0);
        for lj in a.1..=b.1 {
            for li in a.0..=b.0 {
                let z = (self.z)(li, lj);
                if z.is_finite() {
                    (lo, hi, finite) = (lo.min(z), hi.max(z), finite + 1);
                }
            }
        }
        let samples = (b.0 - a.0 + 1) * (b.1 - a.1 + 1);
        let fill = match finite {
            0 => Fill::Empty,
            n if n == samples => Fill::Full,
            _ => Fill::Partial,
        };
        Census { fill, lo, hi, finite, samples }
    }

    /// The prisms of a `w` × `h` tile's pieces, halved until each is full and within `tol`
    /// (bounded by its coarse surface and error), holds no finite sample (left out), or is one
    /// fine cell. With `gate`, a piece with holes stands too when at least half its samples are
    /// finite and their heights span at most 2 `tol` (or it is one fine cell with a fine
    /// triangle), bounded by a flat prism over the whole piece from the lowest to the highest of
    /// them: it holds every fine triangle of the piece, which lies over the piece with corners
    /// among those heights. (So a gate reaches over a hole by less than half a piece.)
    fn shell(&self, (w, h): (usize, usize), tol: f64, gate: bool) -> Shell {
        let (z, xy, thick) = (self.z, self.xy, self.thick);
        let mut out = Shell::default();
        let mut stack = vec![((0usize, 0usize), (w - 1, h - 1))];
        while let Some((a, b)) = stack.pop() {
            let c = self.census(a, b);
            let corners = [(a.0, a.1), (b.0, a.1), (b.0, b.1), (a.0, b.1)];
            let single = b.0 - a.0 <= 1 && b.1 - a.1 <= 1;
            // A full piece's error, computed once: it decides whether the piece stands, and bounds it.
            let error = (c.fill == Fill::Full).then(|| cell_error(a, b, z));
            // A gate's piece with holes that stands as one flat prism.
            let flat = gate && (single || (2 * c.finite >= c.samples && c.hi - c.lo <= 2.0 * tol));
            match (c.fill, error) {
                (Fill::Empty, _) => {}
                (Fill::Full, Some(e)) if single || e <= tol => {
                    let half = e + thick;
                    let bounds = corners.map(|(i, j)| (z(i, j) - half, z(i, j) + half));
                    prism(&mut out, &corners.map(|(i, j)| xy(i, j)), &bounds, self.flip)
                }
                (Fill::Partial, _) if flat => {
                    // (A fine cell with fewer than three finite corners has no fine triangle.)
                    if single && c.finite < 3 {
                        continue;
                    }
                    let bounds = [(c.lo - thick, c.hi + thick); 4];
                    prism(&mut out, &corners.map(|(i, j)| xy(i, j)), &bounds, self.flip)
                }
                // One fine cell with a hole at a corner: a prism over each of its fine triangles
                // whose corners are finite (the triangle itself, thickened), nothing elsewhere.
                (Fill::Partial, _) if single => {
                    for tri in [[corners[0], corners[1], corners[2]], [corners[0], corners[2], corners[3]]] {
                        if tri.iter().all(|&(i, j)| z(i, j).is_finite()) {
                            let bounds = tri.map(|(i, j)| (z(i, j) - thick, z(i, j) + thick));
                            // Each corner pushed out from the triangle's centroid: every edge moves out.
                            let p = tri.map(|(i, j)| DVec2::from((self.pos)(i, j)));
                            let c = (p[0] + p[1] + p[2]) / 3.0;
                            let push = self.push;
                            let out_xy =
                                p.map(|q| q + (q - c).normalize_or_zero() * push).map(|q| [q.x as f32, q.y as f32]);
                            prism(&mut out, &out_xy, &bounds, self.flip);
                        }
                    }
                }
                _ => {
                    let (mi, mj) = ((a.0 + b.0) / 2, (a.1 + b.1) / 2);
                    let xs = if b.0 - a.0 > 1 { vec![a.0, mi, b.0] } else { vec![a.0, b.0] };
                    let ys = if b.1 - a.1 > 1 { vec![a.1, mj, b.1] } else { vec![a.1, b.1] };
                    for jj in ys.windows(2) {
                        for ii in xs.windows(2) {
                            stack.push(((ii[0], jj[0]), (ii[1], jj[1])));
                        }
                    }
                }
            }
        }
        out
    }
}

/// Appends a closed prism over the convex polygon `corners` (a triangle or a quadrilateral,
/// counter-clockwise in the grid's frame), its top at the corners' upper bounds and its bottom at
/// their lower ones, every face wound outwards (counter-clockwise seen from outside) in world
/// space: `flip` when the grid's frame is left-handed there (its rows run clockwise from its
/// columns), which turns its counter-clockwise into clockwise.
fn prism(slab: &mut Shell, corners: &[[f32; 2]], bounds: &[(f64, f64)], flip: bool) {
    let base = slab.vertices.len() as u32;
    let m = corners.len() as u32;
    let miters = miters(corners);
    let tops: Vec<f32> = bounds.iter().map(|b| bound_f32(b.1, 1.0)).collect();
    let bottoms: Vec<f32> = bounds.iter().map(|b| bound_f32(b.0, -1.0)).collect();
    // The steepest slope of the top's and the bottom's triangles, over 8, rounded up.
    let slope = steepest(corners, &tops).max(steepest(corners, &bottoms));
    let slope = ((slope / 8.0 * 127.0).ceil()).min(127.0) as i8;
    for (side, z) in [(127, &tops), (-127, &bottoms)] {
        for ((c, z), mi) in corners.iter().zip(z).zip(&miters) {
            slab.vertices.push(ShellVertex { pos: [c[0], c[1], *z], out: [mi[0], mi[1], slope, side] });
        }
    }
    let mut tri = |a: u32, b: u32, c: u32| slab.indices.extend_from_slice(&if flip { [a, c, b] } else { [a, b, c] });
    let (t, u) = (base, base + m);
    for k in 1..m - 1 {
        tri(t, t + k, t + k + 1); // the top, facing up
        tri(u, u + k + 1, u + k); // the bottom, facing down
    }
    for k in 0..m {
        // A wall below the top's edge k, facing away from the polygon.
        let (e0, e1) = (t + k, t + (k + 1) % m);
        tri(e0, e1 + m, e1);
        tri(e0, e0 + m, e1 + m);
    }
}

/// Per corner of the convex polygon `corners` (either winding), its miter over 4 as snorm8: the
/// vector `m` with `m . n = 1` for the outward unit normals `n` of both edges at the corner, so
/// that moving every corner by `t m` moves every edge out by `t`. Clamped to length 4 (a corner
/// sharper than 29 degrees moves its edges out by less).
fn miters(corners: &[[f32; 2]]) -> Vec<[i8; 2]> {
    let p: Vec<DVec2> = corners.iter().map(|c| DVec2::new(c[0].into(), c[1].into())).collect();
    let n = p.len();
    let area: f64 = (0..n).map(|k| p[k].perp_dot(p[(k + 1) % n])).sum();
    // The outward normal of edge a -> b: to its right on a counter-clockwise polygon.
    let normal = |a: DVec2, b: DVec2| {
        let d = (b - a).normalize_or_zero();
        if area >= 0.0 {
            DVec2::new(d.y, -d.x)
        } else {
            DVec2::new(-d.y, d.x)
        }
    };
    (0..n)
        .map(|k| {
            let (prev, at, next) = (p[(k + n - 1) % n], p[k], p[(k + 1) % n]);
            let (n1, n2) = (normal(prev, at), normal(at, next));
            let m = (n1 + n2) / (1.0 + n1.dot(n2)).max(1.0 / 16.0);
            let m = m.clamp_length_max(4.0) / 4.0;
            [m.x, m.y].map(|c| (c * 127.0).round().clamp(-127.0, 127.0) as i8)
        })
        .collect()
}

/// The steepest slope (rise over run) of the triangles (0, k, k + 1) over the polygon `corners`
/// at heights `z`.
fn steepest(corners: &[[f32; 2]], z: &[f32]) -> f64 {
    let p = |k: usize| glam::DVec3::new(corners[k][0].into(), corners[k][1].into(), z[k].into());
    (1..corners.len() - 1)
        .map(|k| {
            let n = (p(k) - p(0)).cross(p(k + 1) - p(0));
            if n.z == 0.0 {
                f64::INFINITY
            } else {
                n.truncate().length() / n.z.abs()
            }
        })
        .fold(0.0, f64::max)
}

/// `exact` as f32, rounded up for a top (`side` > 0) and down for a bottom, so that the f32 still
/// bounds the f64.
fn bound_f32(exact: f64, side: f32) -> f32 {
    if side > 0.0 {
        super::f32_at_least(exact)
    } else {
        super::f32_at_most(exact)
    }
}

/// The slab of a height-field tile of `w` × `h` samples from its own vertices, as drawn:
/// `vertex(li, lj)` the tile's vertex at local sample (li, lj) (`u32::MAX` where none: a hole, or
/// a sample no triangle uses), `grid_xy` the sample's origin-relative (x, y) from its grid, used
/// where it has no vertex. The same slab whether the tile was just built or read back from bytes.
pub fn tile_slab(
    tile: &super::TileMesh,
    (w, h): (usize, usize),
    vertex: impl Fn(usize, usize) -> u32,
    grid_xy: impl Fn(usize, usize) -> (f64, f64),
) -> Option<Slab> {
    let at = |li: usize, lj: usize| tile.positions.get(vertex(li, lj) as usize);
    let pos = |li: usize, lj: usize| match at(li, lj) {
        Some(p) => (p[0] as f64, p[1] as f64),
        None => grid_xy(li, lj),
    };
    let slab = heightfield_slab(w, h, pos, |li, lj| at(li, lj).map_or(f64::NAN, |p| p[2] as f64))?;
    let blocks = super::blocks::height_blocks(w, h, |li, lj| at(li, lj).copied());
    Some(Slab { blocks: blocks.into(), ..slab })
}

/// The largest vertical distance between the fine surface over the lattice cell `a..=b` (local
/// sample indices; every sample finite) and the cell's coarse triangles (corners a, b, c and a, c,
/// d counter-clockwise from `a`, split along a-c as the fine cells are). Both are piecewise linear,
/// so the distance is largest at a vertex of their overlay: a fine sample, or where the coarse
/// diagonal crosses a fine edge (a column line, a row line or a fine cell's diagonal).
fn cell_error(a: (usize, usize), b: (usize, usize), z: &impl Fn(usize, usize) -> f64) -> f64 {
    let (sx, sy) = ((b.0 - a.0) as f64, (b.1 - a.1) as f64);
    let (za, zb, zc, zd) = (z(a.0, a.1), z(b.0, a.1), z(b.0, b.1), z(a.0, b.1));
    let coarse =
        |u: f64, v: f64| if u >= v { za + u * (zb - za) + v * (zc - zb) } else { za + u * (zc - zd) + v * (zd - za) };
    // The fine surface at local grid coordinates (x, y) from `a`, on its triangles.
    let fine = |x: f64, y: f64| {
        let (i, j) = ((x.floor() as usize).min(b.0 - a.0 - 1), (y.floor() as usize).min(b.1 - a.1 - 1));
        let (fx, fy) = (x - i as f64, y - j as f64);
        let at = |di: usize, dj: usize| z(a.0 + i + di, a.1 + j + dj);
        if fx >= fy {
            at(0, 0) + fx * (at(1, 0) - at(0, 0)) + fy * (at(1, 1) - at(1, 0))
        } else {
            at(0, 0) + fx * (at(1, 1) - at(0, 1)) + fy * (at(0, 1) - at(0, 0))
        }
    };
    let mut e = 0.0f64;
    for lj in a.1..=b.1 {
        for li in a.0..=b.0 {
            let (u, v) = ((li - a.0) as f64 / sx, (lj - a.1) as f64 / sy);
            e = e.max((z(li, lj) - coarse(u, v)).abs());
        }
    }
    // The coarse diagonal (t sx, t sy), t in 0..1, crosses column lines at t = i / sx, row lines at
    // t = j / sy and fine diagonals (y - x an integer) at t = k / (sy - sx).
    let mut ts: Vec<f64> = (1..b.0 - a.0).map(|i| i as f64 / sx).chain((1..b.1 - a.1).map(|j| j as f64 / sy)).collect();
    if sx != sy {
        let span = (sy - sx).abs() as usize;
        ts.extend((1..span).map(|k| k as f64 / (sy - sx).abs()));
    }
    for t in ts {
        e = e.max((fine(t * sx, t * sy) - (za + t * (zc - za))).abs());
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dipping, wavy tile rotated 30 degrees, with scattered holes (and a hole-free variant).
    #[allow(clippy::type_complexity)]
    fn tile(holes: bool) -> (impl Fn(usize, usize) -> (f64, f64), impl Fn(usize, usize) -> f64) {
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let pos = move |i: usize, j: usize| {
            let (u, v) = (i as f64 * 25.0, j as f64 * 25.0);
            (c * u - s * v + 10.0, s * u + c * v - 20.0)
        };
        let z = move |i: usize, j: usize| {
            if holes && ((i * 7 + j * 3).is_multiple_of(11) || i + j < 6) {
                f64::NAN
            } else {
                -0.1 * i as f64 * 25.0 + 8.0 * (j as f64 * 0.7).sin() + 3.0 * (i as f64 * 1.3).cos()
            }
        };
        (pos, z)
    }

    /// The slab's two shells: the slab itself and its gate.
    fn shells(s: &Slab) -> [(&'static str, Shell); 2] {
        [("slab", Shell { vertices: s.vertices.clone(), indices: s.indices.clone() }), ("gate", s.gate.clone())]
    }

    /// Heights at (x, y) of the shell's top (side +1) and bottom (side -1) triangles covering it.
    fn heights_at(s: &Shell, x: f64, y: f64) -> (Vec<f64>, Vec<f64>) {
        let (mut tops, mut bottoms) = (Vec::new(), Vec::new());
        for t in s.indices.chunks_exact(3) {
            let v = [t[0], t[1], t[2]].map(|k| s.vertices[k as usize]);
            if v[0].side() != v[1].side() || v[1].side() != v[2].side() {
                continue; // a wall
            }
            let p = v.map(|q| DVec2::new(q.pos[0] as f64, q.pos[1] as f64));
            let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
            if area.abs() < 1e-12 {
                continue;
            }
            let q = DVec2::new(x, y);
            let l1 = (p[2] - p[1]).perp_dot(q - p[1]) / area;
            let l2 = (p[0] - p[2]).perp_dot(q - p[2]) / area;
            let l3 = 1.0 - l1 - l2;
            // f32 vertices: points on a shared edge may fall a few ulps outside both triangles.
            if l1 < -1e-5 || l2 < -1e-5 || l3 < -1e-5 {
                continue;
            }
            let zz = l1 * v[0].pos[2] as f64 + l2 * v[1].pos[2] as f64 + l3 * v[2].pos[2] as f64;
            if v[0].side() > 0.0 {
                tops.push(zz)
            } else {
                bottoms.push(zz)
            }
        }
        (tops, bottoms)
    }

    #[test]
    fn every_point_of_the_fine_triangles_lies_between_a_top_and_a_bottom_over_it() {
        for holes in [false, true] {
            for (w, h) in [(2, 2), (3, 9), (17, 12), (40, 33)] {
                let (pos, z) = tile(holes);
                let Some(slab) = heightfield_slab(w, h, &pos, &z) else {
                    assert!(holes && w * h <= 4);
                    continue;
                };
                for (name, s) in shells(&slab) {
                    if name == "gate" && s.indices.is_empty() {
                        continue; // no gate: the slab is tested alone
                    }
                    shell_holds_the_fine_triangles(&s, (w, h), (&pos, &z), &format!("{name} {w} {h} {holes}"));
                }
            }
        }
    }

    /// Every point of the tile's fine triangles has a top of `s` at or above it and a bottom at or
    /// below it.
    #[allow(clippy::type_complexity)]
    fn shell_holds_the_fine_triangles(
        s: &Shell,
        (w, h): (usize, usize),
        (pos, z): (&dyn Fn(usize, usize) -> (f64, f64), &dyn Fn(usize, usize) -> f64),
        what: &str,
    ) {
        for t in s.indices.chunks_exact(3) {
            assert!(t.iter().all(|&k| (k as usize) < s.vertices.len()));
        }
        let mut checked = 0;
        for lj in 0..h - 1 {
            for li in 0..w - 1 {
                for tri in [[(0, 0), (1, 0), (1, 1)], [(0, 0), (1, 1), (0, 1)]] {
                    let c = tri.map(|(di, dj)| (li + di, lj + dj));
                    if c.iter().any(|&(i, j)| !z(i, j).is_finite()) {
                        continue;
                    }
                    for bary in [[1.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [1.0 / 3.0; 3]] {
                        let mix =
                            |f: &dyn Fn(usize, usize) -> f64| (0..3).map(|k| bary[k] * f(c[k].0, c[k].1)).sum::<f64>();
                        let (x, y) = (mix(&|i, j| pos(i, j).0), mix(&|i, j| pos(i, j).1));
                        let zz = mix(&|i, j| z(i, j));
                        let (tops, bottoms) = heights_at(s, x, y);
                        assert!(
                            tops.iter().any(|&t| t >= zz - 1e-4),
                            "no top over ({li}, {lj}) {zz}: {tops:?} {what} {x} {y}"
                        );
                        assert!(bottoms.iter().any(|&b| b <= zz + 1e-4), "no bottom under ({li}, {lj}) {what}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 0);
    }

    #[test]
    fn a_smooth_tile_gets_a_thin_slab_and_holes_are_left_out() {
        // A plane: every cell's coarse triangles are the surface, so the slab is the plane itself.
        let plane = |i: usize, j: usize| 0.5 * i as f64 - 0.25 * j as f64;
        let s = heightfield_slab(33, 33, |i, j| (i as f64 * 10.0, j as f64 * 10.0), plane).unwrap();
        assert_eq!((s.vertices.len(), s.indices.len()), (8, 36), "one prism");
        assert!(s.gate.indices.is_empty(), "a gate no smaller than the slab is left out");
        for v in s.vertices.iter().map(|v| v.pos) {
            let want = 0.05 * v[0] as f64 - 0.025 * v[1] as f64;
            assert!((v[2] as f64 - want).abs() < 0.02, "{v:?}");
        }
        // A tile whose left half is a hole: no top reaches over the hole.
        let half = |i: usize, j: usize| if i < 16 { f64::NAN } else { plane(i, j) };
        let s = heightfield_slab(33, 33, |i, j| (i as f64 * 10.0, j as f64 * 10.0), half).unwrap();
        let (tops, _) = heights_at(&shells(&s)[0].1, 50.0, 160.0);
        assert!(tops.is_empty());
        let (tops, _) = heights_at(&shells(&s)[0].1, 250.0, 160.0);
        assert!(!tops.is_empty());
        assert!(heightfield_slab(5, 5, |i, j| (i as f64, j as f64), |_, _| f64::NAN).is_none());
    }

    #[test]
    fn every_prism_is_closed_and_wound_outwards() {
        for (yflip, holes) in [(false, false), (false, true), (true, true)] {
            let (pos, z) = tile(holes);
            let pos = move |i: usize, j: usize| {
                let (x, y) = pos(i, j);
                if yflip {
                    (x, -y)
                } else {
                    (x, y)
                }
            };
            let slab = heightfield_slab(17, 12, pos, &z).unwrap();
            assert!(!slab.gate.indices.is_empty() && slab.gate.indices.len() < slab.indices.len());
            for (name, s) in shells(&slab) {
                prisms_are_closed_and_wound_outwards(&s, &format!("{name} {yflip} {holes}"));
            }
        }
    }

    /// Each prism's faces enclose a positive volume (outward winding) and every directed edge is
    /// matched by its reverse (closed), prism by prism (their vertices are their own).
    fn prisms_are_closed_and_wound_outwards(s: &Shell, what: &str) {
        let mut edges = std::collections::HashMap::new();
        let mut volume = 0.0f64;
        for t in s.indices.chunks_exact(3) {
            let p = [t[0], t[1], t[2]].map(|k| glam::DVec3::from(s.vertices[k as usize].pos.map(f64::from)));
            volume += p[0].dot(p[1].cross(p[2])) / 6.0;
            for e in 0..3 {
                *edges.entry((t[e], t[(e + 1) % 3])).or_insert(0) += 1;
            }
        }
        assert!(edges.iter().all(|(&(a, b), &c)| c == 1 && edges.get(&(b, a)) == Some(&1)), "{what}");
        assert!(volume > 0.0, "{what}: {volume}");
    }

    /// Moved by its miter (decoded from snorm8), every corner of a convex polygon moves both its
    /// edges out by about 1, in either winding; a straight corner moves along the edge's normal.
    #[test]
    fn miters_move_every_edge_out_by_one() {
        let (c, s) = (0.6f64, 0.8f64);
        let rot = |x: f64, y: f64| [(c * x - s * y) as f32, (s * x + c * y) as f32];
        let polygons = [
            vec![rot(0.0, 0.0), rot(20.0, 0.0), rot(20.0, 5.0), rot(0.0, 5.0)],
            vec![rot(0.0, 0.0), rot(20.0, 0.0), rot(20.0, 20.0)],
            vec![rot(0.0, 0.0), rot(10.0, 0.0), rot(20.0, 0.0), rot(20.0, 12.0), rot(0.0, 12.0)],
        ];
        for poly in polygons {
            for winding in [false, true] {
                let mut p = poly.clone();
                if winding {
                    p.reverse();
                }
                let m = miters(&p);
                let v: Vec<DVec2> = p.iter().map(|q| DVec2::new(q[0].into(), q[1].into())).collect();
                let centre = v.iter().sum::<DVec2>() / v.len() as f64;
                for k in 0..v.len() {
                    let (a, b) = (v[k], v[(k + 1) % v.len()]);
                    // The edge's outward normal: away from the centre.
                    let mut n = (b - a).perp().normalize();
                    if n.dot(a - centre) < 0.0 {
                        n = -n;
                    }
                    for (i, q) in [(k, a), (k + 1, b)] {
                        let mi = m[i % v.len()];
                        let mv = DVec2::new(mi[0] as f64, mi[1] as f64) * 4.0 / 127.0;
                        let out = mv.dot(n);
                        assert!((0.93..=1.07).contains(&out), "{p:?} corner {q} edge {k}: {out}");
                    }
                }
            }
        }
    }

    /// The slope a prism's vertices carry bounds its top's and bottom's slopes.
    #[test]
    fn the_slope_prisms_carry_bounds_their_tops() {
        let mut sh = Shell::default();
        let corners = [[0.0f32, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        // Top rising 3 m over 10 m along x and 1 m along y, bottom flat.
        let bounds = [(0.0, 0.0), (0.0, 3.0), (0.0, 4.0), (0.0, 1.0)];
        prism(&mut sh, &corners, &bounds, false);
        let want = (0.3f64 * 0.3 + 0.1 * 0.1).sqrt();
        for v in &sh.vertices {
            let got = v.out[2] as f64 / 127.0 * 8.0;
            assert!(got >= want && got < want + 8.0 / 127.0, "{got} {want}");
        }
        assert_eq!(sh.vertices.iter().filter(|v| v.side() > 0.0).count(), 4);
    }
}

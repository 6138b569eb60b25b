//! Cell coordinates: how a grid coloured by a cell property keeps its picture at every level.
//!
//! A merged face covers many cells (Jia et al. merge 2^h x 2^h columns of a layer into one face),
//! so a colour per face would show the mean of their values. Instead every vertex of a face
//! carries *cell coordinates* (`TileMesh::grid_uv` of a grid tile), the lit pass interpolates them
//! over the face and each fragment looks its own cell's value up (draw.wgsl `fs_cells`): a coarse
//! level changes the geometry within its error and the colours not at all.
//!
//! Coordinates are doubled lattice coordinates relative to the block (tile): a pillar at column
//! `pi` has `2 (pi - i0)`, a cell's centre `2 (ci - i0) + 1`; the same along j, and along k every
//! face of layer `k` has `2 k + 1` (merged faces never span layers). A fragment's cell is
//! `floor(c / 2)`. On a face of cell (ci, cj, k) the coordinate across the face is the cell's
//! centre, the ones along it come from the pillars the vertices lie on; a vertex on no pillar (a
//! fault's crossing on the edge of a top face, a fan's centre) takes the cell's centre, which keeps
//! every fragment of a level-0 face in its own cell. Merged faces keep only pillar vertices
//! (`exact_shape`), so their coordinates are exact integers and interpolate as the lattice does.
//! The pieces of faulted faces are [`FLAT`]: coloured by their vertices' value (their cell's), and
//! they merge into strips only where all their values are equal.
//!
//! Packed as `i | j << 8 | k << 16` (blocks up to [`MAX_BLOCK`] columns wide, up to [`MAX_LAYERS`] layers).
//! The tile's table of cell values ([`cell_table`]) is read back from level 0: the centroid of each
//! fine triangle lies in its face's cell, whose value every vertex of the face carries.

use super::faces::Face;
use super::poly::{fan_apex, Verts, NO_PILLAR};
use glam::{DVec2, DVec3};

/// Grids with more layers keep a colour per face (`k` has 16 bits, one value kept for [`FLAT`]).
pub const MAX_LAYERS: usize = (1 << 15) - 2;
/// The coordinates of a face coloured by its vertices' value, not per cell: the pieces a fault
/// cuts faces into (one cell each) and the strips they merge into (pieces of one value).
pub const FLAT: u32 = 0xffff << 16;
/// ... and so do grids cut into blocks of more columns (`i` and `j` have 8 bits).
pub const MAX_BLOCK: usize = 127;

/// Packs doubled block-relative coordinates.
#[inline]
pub fn pack(i2: u32, j2: u32, k2: u32) -> u32 {
    i2 | j2 << 8 | k2 << 16
}

/// The doubled coordinates of a packed word.
#[inline]
pub fn unpack(c: u32) -> [u32; 3] {
    [c & 0xff, (c >> 8) & 0xff, c >> 16]
}

/// The cell coordinates of every vertex a level-0 face uses (`face.verts`, then any vertex only
/// its triangles use: a fan's centre), in that order. `(i0, j0)`: the block's first column;
/// `ni`: the grid's columns (pillar ids are `pj * (ni + 1) + pi`).
pub(crate) fn level0(face: &Face, verts: &Verts, (i0, j0): (u32, u32), ni: usize) -> Vec<u32> {
    if !face.whole {
        return vec![FLAT; face.verts.len() + face.tris.iter().flatten().filter(|v| !face.verts.contains(v)).count()];
    }
    let (ci2, cj2, k2) = (2 * (face.ci - i0) + 1, 2 * (face.cj - j0) + 1, 2 * face.k + 1);
    let centre = pack(ci2, cj2, k2);
    let at = |v: u32| {
        let p = verts.pillar[v as usize];
        if p == NO_PILLAR {
            return centre;
        }
        let (pi, pj) = (p % (ni as u32 + 1), p / (ni as u32 + 1));
        let (pi2, pj2) = (2 * (pi - i0), 2 * (pj - j0));
        match face.dir {
            0 | 1 => pack(ci2, pj2, k2),
            2 | 3 => pack(pi2, cj2, k2),
            _ => pack(pi2, pj2, k2),
        }
    };
    let mut out: Vec<u32> = face.verts.iter().map(|&v| at(v)).collect();
    for &v in face.tris.iter().flatten() {
        if !face.verts.contains(&v) {
            out.push(centre);
        }
    }
    out
}

/// A strip of fault pieces may merge (see the module) only when its pieces have one value.
pub(crate) fn strip_ok(members: &[u32], faces: &[Face]) -> bool {
    members.windows(2).all(|w| faces[w[0] as usize].value.to_bits() == faces[w[1] as usize].value.to_bits())
}

/// The coordinates face `f` gives vertex `v` (`Face::lat` is aligned with `verts` and then the
/// triangles' other vertices); None if `f` does not use `v`.
pub(crate) fn of(f: &Face, v: u32) -> Option<u32> {
    if let Some(w) = f.verts.iter().position(|&u| u == v) {
        return f.lat.get(w).copied();
    }
    let mut extra = f.verts.len();
    for &u in f.tris.iter().flatten() {
        if f.verts.contains(&u) {
            continue;
        }
        if u == v {
            return f.lat.get(extra).copied();
        }
        extra += 1;
    }
    None
}

/// A merged face may carry cell coordinates only if every vertex it keeps lies on a pillar
/// (exact lattice coordinates) and its fan needs no new centre vertex.
pub(crate) fn exact_shape(reduced: &[u32], verts: &Verts) -> bool {
    reduced.iter().all(|&v| verts.pillar[v as usize] != NO_PILLAR)
        && (reduced.len() == 3 || fan_apex(reduced, verts).is_some())
}

/// The two lattice axes along a face of direction `dir` (the third is fixed across it).
fn along(dir: u8) -> [usize; 2] {
    match dir {
        0 | 1 => [1, 2],
        2 | 3 => [0, 2],
        _ => [0, 1],
    }
}

/// How far the colours of a merged face can move: the largest distance between a removed
/// vertex's position and the point of the merged face that its cell coordinates interpolate to
/// (outline vertices along the segment that replaced them, inner ones over the face's fan). This
/// is the error of the lattice's map on the face, along it as well as across it; `lat(v)` gives a
/// member's coordinates of `v`.
pub(crate) fn drift(
    dir: u8,
    outline: &[u32],
    inner: &[u32],
    reduced: &[u32],
    drop: &[bool],
    verts: &Verts,
    lat: &dyn Fn(u32) -> Option<u32>,
) -> f64 {
    let ax = along(dir);
    let uv = |v: u32| lat(v).map(unpack).map(|c| DVec2::new(c[ax[0]] as f64, c[ax[1]] as f64));
    let mut err = 0.0f64;
    for (w, a, c) in super::poly::removed_spans(outline, drop) {
        let (Some(la), Some(lc), Some(lv)) = (uv(outline[a]), uv(outline[c]), uv(outline[w])) else { continue };
        let d = lc - la;
        let t = if d.length_squared() > 0.0 { ((lv - la).dot(d) / d.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
        let (pa, pc) = (verts.p(outline[a]), verts.p(outline[c]));
        err = err.max((pa + t * (pc - pa) - verts.p(outline[w])).length());
    }
    if reduced.len() >= 3 && !inner.is_empty() {
        let apex = if reduced.len() == 3 { Some(0) } else { fan_apex(reduced, verts) };
        let corners: Option<Vec<DVec2>> = reduced.iter().map(|&v| uv(v)).collect();
        if let (Some(a), Some(c)) = (apex, corners) {
            let n = reduced.len();
            for &v in inner {
                let Some(q) = uv(v) else { continue };
                let hit = (1..n - 1).find_map(|s| {
                    let tri = [a, (a + s) % n, (a + s + 1) % n];
                    barycentric(q, tri.map(|x| c[x])).map(|b| (tri, b))
                });
                if let Some((tri, b)) = hit {
                    let p: DVec3 = (0..3).map(|x| b[x] * verts.p(reduced[tri[x]])).sum();
                    err = err.max((p - verts.p(v)).length());
                }
            }
        }
    }
    err
}

/// Barycentric coordinates of `q` in triangle `t` (a little outside counts as inside).
fn barycentric(q: DVec2, t: [DVec2; 3]) -> Option<[f64; 3]> {
    let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], q - t[0]);
    let det = e1.perp_dot(e2);
    if det.abs() < 1e-12 {
        return None;
    }
    let (b1, b2) = (d.perp_dot(e2) / det, e1.perp_dot(d) / det);
    let b0 = 1.0 - b1 - b2;
    const EPS: f64 = 1e-9;
    (b0 >= -EPS && b1 >= -EPS && b2 >= -EPS).then_some([b0, b1, b2])
}

/// A grid tile's cell values for the lit pass (`SceneGeometry::sample_values`): its columns
/// (bw, bh) and layers nk, and the values of cells (k, j, i) at `(k * bh + j) * bw + i`, read off
/// its fine level (each fine triangle's centroid lies in its cell; its vertices carry the cell's
/// value; [`FLAT`] faces are not in the table). Cells no fine triangle lies in (never drawn) are
/// `f32::INFINITY`; None unless the tile carries cell coordinates and values.
pub fn cell_table(t: &crate::lod::TileMesh) -> Option<([u32; 3], Vec<f32>)> {
    if t.grid_uv.is_empty() || t.grid_uv.len() != t.positions.len() || t.values.len() != t.positions.len() {
        return None;
    }
    let mut hi = [0u32; 3];
    for &c in t.grid_uv.iter().filter(|&&c| c != FLAT) {
        let u = unpack(c);
        for a in 0..3 {
            hi[a] = hi[a].max(u[a]);
        }
    }
    let dims = hi.map(|h| h.div_ceil(2).max(1));
    let mut table = vec![f32::INFINITY; (dims[0] * dims[1] * dims[2]) as usize];
    for tri in t.fine.chunks_exact(3) {
        if t.grid_uv[tri[0] as usize] == FLAT {
            continue;
        }
        let mut s = [0u32; 3];
        for &v in tri {
            let u = unpack(t.grid_uv[v as usize]);
            for a in 0..3 {
                s[a] += u[a];
            }
        }
        // floor(mean / 2) = floor(sum / 6).
        let c = s.map(|x| x / 6);
        let c = [0, 1, 2].map(|a| c[a].min(dims[a] - 1));
        table[((c[2] * dims[1] + c[1]) * dims[0] + c[0]) as usize] = t.values[tri[0] as usize];
    }
    Some((dims, table))
}

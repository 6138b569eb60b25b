//! Small geometry helpers of the grid builder: a fast hash map, a block's vertex table (vertices
//! keyed by their exact f32 position and their region), and the triangulation of the convex
//! polygons that faces are made of.

use glam::DVec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A multiply-rotate hash (the keys are vertex positions and small integer tuples; SipHash's
/// DoS resistance buys nothing here and costs a third of the build).
#[derive(Default)]
pub(crate) struct FastHasher(u64);

impl FastHasher {
    #[inline]
    fn add(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for FastHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.add(u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]));
        }
        for &b in chunks.remainder() {
            self.add(b as u64);
        }
    }
    fn write_u8(&mut self, v: u8) {
        self.add(v as u64)
    }
    fn write_u32(&mut self, v: u32) {
        self.add(v as u64)
    }
    fn write_i32(&mut self, v: i32) {
        self.add(v as u32 as u64)
    }
    fn write_u64(&mut self, v: u64) {
        self.add(v)
    }
    fn write_usize(&mut self, v: usize) {
        self.add(v as u64)
    }
}

pub(crate) type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FastHasher>>;

pub(crate) const NO_PILLAR: u32 = u32::MAX;

/// Merged faces may bend inwards at a kept vertex by this much (sine of the angle): surfaces
/// that curve make the kept vertices of a merged outline slightly reflex; real concavity (an L
/// shape) turns by 90 degrees.
pub(crate) const CONVEX_TOL: f64 = 0.02;

/// A vertex whose outline turns by less than this (sine of the angle, about 3 degrees) lies on a
/// straight side for the choice of a fan apex.
pub(crate) const STRAIGHT: f64 = 0.05;

/// The vertices of one block. A vertex is a position (as the tile will store it: f32 relative
/// to the origin, compared bit for bit) of one region: the surfaces of two regions meeting at a
/// boundary are separate closed surfaces and share no vertex, so that merging one never pins the
/// other. `border` marks vertices on a seam with another block (kept at every level), `pillar` the
/// global pillar a vertex lies on (`pj * (ni + 1) + pi`, or [`NO_PILLAR`]).
pub(crate) struct Verts {
    map: FastMap<([u32; 3], i32), u32>,
    pub pos: Vec<[f64; 3]>,
    pub rel: Vec<[f32; 3]>,
    pub border: Vec<bool>,
    pub pillar: Vec<u32>,
    origin: DVec3,
}

impl Verts {
    pub fn new(origin: DVec3) -> Self {
        Self {
            map: FastMap::default(),
            pos: Vec::new(),
            rel: Vec::new(),
            border: Vec::new(),
            pillar: Vec::new(),
            origin,
        }
    }

    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// The vertex at world position `p` of `region` (created on first use).
    pub fn get(&mut self, p: [f64; 3], region: i32, border: bool, pillar: u32) -> u32 {
        // `+ 0.0` turns -0.0 into +0.0, so that equal positions have equal bits.
        let rel = [
            (p[0] - self.origin.x) as f32 + 0.0,
            (p[1] - self.origin.y) as f32 + 0.0,
            (p[2] - self.origin.z) as f32 + 0.0,
        ];
        let key = (rel.map(f32::to_bits), region);
        let next = self.pos.len() as u32;
        let v = *self.map.entry(key).or_insert(next);
        if v == next {
            self.pos.push(p);
            self.rel.push(rel);
            self.border.push(border);
            self.pillar.push(pillar);
        } else {
            let b = &mut self.border[v as usize];
            *b |= border;
            if self.pillar[v as usize] == NO_PILLAR {
                self.pillar[v as usize] = pillar;
            }
        }
        v
    }

    pub fn p(&self, v: u32) -> DVec3 {
        DVec3::from_array(self.pos[v as usize])
    }
}

/// `poly` without consecutive repeats (the ring closed), or None when fewer than 3 remain.
pub(crate) fn clean(poly: &[u32]) -> Option<Vec<u32>> {
    let mut out: Vec<u32> = Vec::with_capacity(poly.len());
    for &v in poly {
        if out.last() != Some(&v) {
            out.push(v);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    (out.len() >= 3).then_some(out)
}

/// Newell's normal of a polygon (length = twice its area for a planar one).
pub(crate) fn newell(poly: &[u32], verts: &Verts) -> DVec3 {
    let mut n = DVec3::ZERO;
    let c = verts.p(poly[0]);
    for w in 0..poly.len() {
        let a = verts.p(poly[w]) - c;
        let b = verts.p(poly[(w + 1) % poly.len()]) - c;
        n += a.cross(b);
    }
    n
}

/// Whether a polygon has (numerically) zero area: twice its area under 1e-12 of its perimeter
/// squared.
pub(crate) fn zero_area(poly: &[u32], verts: &Verts) -> bool {
    let n = newell(poly, verts).length();
    let mut per = 0.0;
    for w in 0..poly.len() {
        per += (verts.p(poly[(w + 1) % poly.len()]) - verts.p(poly[w])).length();
    }
    n.partial_cmp(&(1e-12 * per * per)) != Some(std::cmp::Ordering::Greater)
}

/// Which vertices of a polygon are corners (a turn of more than [`STRAIGHT`], not a point inside
/// a (nearly) straight side: a fan apex on a side's chain would give slivers along it), given its
/// normal `n` (unit).
fn corners(poly: &[u32], verts: &Verts, n: DVec3) -> Vec<bool> {
    let m = poly.len();
    (0..m)
        .map(|w| {
            let a = verts.p(poly[(w + m - 1) % m]);
            let b = verts.p(poly[w]);
            let c = verts.p(poly[(w + 1) % m]);
            let (e1, e2) = (b - a, c - b);
            e1.cross(e2).dot(n).abs() > STRAIGHT * e1.length() * e2.length()
        })
        .collect()
}

/// Whether a polygon is convex (every turn the same way as its normal, up to [`CONVEX_TOL`]) and
/// of non-zero area.
pub(crate) fn convex(poly: &[u32], verts: &Verts) -> bool {
    if poly.len() < 3 || zero_area(poly, verts) {
        return false;
    }
    let n = newell(poly, verts).normalize();
    let m = poly.len();
    (0..m).all(|w| {
        let a = verts.p(poly[(w + m - 1) % m]);
        let b = verts.p(poly[w]);
        let c = verts.p(poly[(w + 1) % m]);
        let (e1, e2) = (b - a, c - b);
        e1.cross(e2).dot(n) >= -CONVEX_TOL * e1.length() * e2.length()
    })
}

/// Triangles of a convex polygon (vertex ids in outward order, already [`clean`] and of non-zero
/// area), wound like the polygon. A fan from a corner whose two neighbours are corners too (then
/// no triangle has zero area: only the two sides through the apex could hold it, and they have
/// no inner points); failing that (straight sides with inner points all round), a fan from a new
/// centre vertex (the mean of the vertices, of `region`).
pub(crate) fn triangulate(poly: &[u32], verts: &mut Verts, region: i32, out: &mut Vec<[u32; 3]>) {
    let first = out.len();
    fan(poly, verts, region, out);
    // A vertex can repeat non-consecutively where two positions round to the same f32: drop the
    // triangles that would repeat it (zero area).
    let mut w = first;
    for r in first..out.len() {
        let t = out[r];
        if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
            out[w] = t;
            w += 1;
        }
    }
    out.truncate(w);
}

/// The corner a convex polygon of more than three vertices is fanned from by [`triangulate`]:
/// one whose two neighbours are corners too; None when it needs a new centre vertex instead.
pub(crate) fn fan_apex(poly: &[u32], verts: &Verts) -> Option<usize> {
    let m = poly.len();
    let n = newell(poly, verts).normalize_or_zero();
    let c = corners(poly, verts, n);
    (0..m).find(|&w| c[w] && c[(w + 1) % m] && c[(w + m - 1) % m])
}

fn fan(poly: &[u32], verts: &mut Verts, region: i32, out: &mut Vec<[u32; 3]>) {
    let m = poly.len();
    if m == 3 {
        out.push([poly[0], poly[1], poly[2]]);
        return;
    }
    if let Some(a) = fan_apex(poly, verts) {
        for s in 1..m - 1 {
            out.push([poly[a], poly[(a + s) % m], poly[(a + s + 1) % m]]);
        }
        return;
    }
    let mut mean = DVec3::ZERO;
    for &v in poly {
        mean += verts.p(v);
    }
    mean /= m as f64;
    let centre = verts.get(mean.to_array(), region, false, NO_PILLAR);
    for w in 0..m {
        let (a, b) = (poly[w], poly[(w + 1) % m]);
        if a != centre && b != centre {
            out.push([centre, a, b]);
        }
    }
}

/// The convex hull of points (t, s) with their vertex ids, counter-clockwise, without points
/// inside straight sides (Andrew's monotone chain). Points with the same id must have the same
/// coordinates (the caller passes each id once).
pub(crate) fn hull(mut pts: Vec<(f64, f64, u32)>) -> Vec<(f64, f64, u32)> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup_by(|a, b| a.2 == b.2);
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: &(f64, f64, u32), a: &(f64, f64, u32), b: &(f64, f64, u32)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut h: Vec<(f64, f64, u32)> = Vec::with_capacity(2 * pts.len());
    for p in pts.iter() {
        while h.len() >= 2 && cross(&h[h.len() - 2], &h[h.len() - 1], p) <= 0.0 {
            h.pop();
        }
        h.push(*p);
    }
    let lower = h.len() + 1;
    for p in pts.iter().rev().skip(1) {
        while h.len() >= lower && cross(&h[h.len() - 2], &h[h.len() - 1], p) <= 0.0 {
            h.pop();
        }
        h.push(*p);
    }
    h.pop();
    h
}

/// Triangles of a simple polygon that need not be convex (vertex ids in outward order, planar up
/// to the surface's bend), wound like it, by ear clipping in the plane of its Newell normal: an
/// ear is a strictly convex corner (turning by more than [`EAR_MIN`]) whose triangle holds no
/// other vertex of the polygon that is not strictly convex, not even on its sides (so no
/// triangle is of zero area and no vertex lies on another triangle's side). None when no such
/// triangulation is found this way (a polygon that is not simple, or one whose straight sides
/// leave only flat ears) or when the triangles' area differs from the polygon's.
pub(crate) fn ear_clip(poly: &[u32], verts: &Verts) -> Option<Vec<[u32; 3]>> {
    let n = newell(poly, verts);
    let area = n.length() / 2.0;
    if poly.len() < 3 || area <= 0.0 {
        return None;
    }
    let nz = n / (2.0 * area);
    let u = nz.any_orthonormal_vector();
    let v = nz.cross(u);
    let o = verts.p(poly[0]);
    let pts: Vec<(f64, f64)> = poly.iter().map(|&x| verts.p(x) - o).map(|d| (d.dot(u), d.dot(v))).collect();
    let cross = |a: usize, b: usize, c: usize| {
        let (pa, pb, pc) = (pts[a], pts[b], pts[c]);
        (pb.0 - pa.0) * (pc.1 - pb.1) - (pb.1 - pa.1) * (pc.0 - pb.0)
    };
    let len = |a: usize, b: usize| ((pts[b].0 - pts[a].0).powi(2) + (pts[b].1 - pts[a].1).powi(2)).sqrt();
    let strictly_convex = |a: usize, b: usize, c: usize| cross(a, b, c) > EAR_MIN * len(a, b) * len(b, c);
    let mut ring: Vec<usize> = (0..poly.len()).collect();
    let mut out = Vec::with_capacity(poly.len() - 2);
    let mut at = 0;
    let mut misses = 0;
    while ring.len() > 3 {
        let m = ring.len();
        let (a, b, c) = (ring[(at + m - 1) % m], ring[at % m], ring[(at + 1) % m]);
        let mut ear = strictly_convex(a, b, c);
        if ear {
            let tol = 1e-12 * (len(a, b) + len(b, c)).powi(2);
            for w in 0..m {
                let p = ring[w];
                if p == a || p == b || p == c || pts[p] == pts[a] || pts[p] == pts[b] || pts[p] == pts[c] {
                    continue;
                }
                let (pp, pn) = (ring[(w + m - 1) % m], ring[(w + 1) % m]);
                if strictly_convex(pp, p, pn) {
                    continue;
                }
                // Inside or on the triangle (a, b, c), which turns counter-clockwise.
                let side = |x: usize, y: usize| {
                    let (px, py, q) = (pts[x], pts[y], pts[p]);
                    (py.0 - px.0) * (q.1 - px.1) - (py.1 - px.1) * (q.0 - px.0)
                };
                if side(a, b) >= -tol && side(b, c) >= -tol && side(c, a) >= -tol {
                    ear = false;
                    break;
                }
            }
        }
        if ear {
            out.push([poly[a], poly[b], poly[c]]);
            ring.remove(at % m);
            at %= ring.len();
            misses = 0;
        } else {
            at = (at + 1) % m;
            misses += 1;
            if misses > m {
                return None;
            }
        }
    }
    let (a, b, c) = (ring[0], ring[1], ring[2]);
    if !strictly_convex(a, b, c) {
        return None;
    }
    out.push([poly[a], poly[b], poly[c]]);
    // Simple and consistently wound: the triangles' areas add up to the polygon's.
    let sum: f64 = out
        .iter()
        .map(|t| {
            let p = t.map(|x| verts.p(x));
            (p[1] - p[0]).cross(p[2] - p[0]).dot(nz) / 2.0
        })
        .sum();
    ((sum - area).abs() <= 1e-6 * area).then_some(out)
}

/// The least turn (sine of the angle) of an ear's corner in [`ear_clip`].
pub(crate) const EAR_MIN: f64 = 1e-6;

/// Each vertex of the ring `outline` that the merge removes (`drop`) with the kept vertices
/// around it, before and after: (removed, before, after) as positions in `outline`.
pub(super) fn removed_spans<'a>(
    outline: &'a [u32],
    drop: &'a [bool],
) -> impl Iterator<Item = (usize, usize, usize)> + 'a {
    let m = outline.len();
    let dropped = move |k: usize| drop[outline[k] as usize];
    (0..m).filter(move |&w| dropped(w)).map(move |w| {
        let mut a = (w + m - 1) % m;
        while dropped(a) && a != w {
            a = (a + m - 1) % m;
        }
        let mut c = (w + 1) % m;
        while dropped(c) && c != w {
            c = (c + 1) % m;
        }
        (w, a, c)
    })
}

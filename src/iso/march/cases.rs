//! The marching-cubes case table, generated at first use from the cube's geometry (no table is
//! hand-written).
//!
//! A case is the cell's corner signs (`mask`, bit `c` set when corner `c` is *above*: value >=
//! w; corner bit 0 = x, 1 = y, 2 = z) plus, per cube face, one bit that only matters when the face
//! is *ambiguous* (its two diagonals carry opposite signs): set when the face's centre counts as
//! above (its above corners are joined across the face, its below corners cut off), clear when
//! it counts as below. The extraction decides that bit from the face's four sample values alone
//! ([`face_centre_above`]), so the two cells sharing a face always draw the same contour on it.
//!
//! For every case the contour on each face is a set of segments between the crossing points of
//! the face's edges (one segment for two crossings; two for an ambiguous face, each cutting off
//! one corner of the side the centre is not on), directed so that the above side lies to the
//! left seen from outside the cube. Every crossing edge lies on two faces and is an end of exactly
//! one segment on each, so the segments form closed, directed loops. Each loop is triangulated
//! (n points, n - 2 triangles) so that every triangle edge lying in a cube face is a contour
//! segment, or else lies in one of the cell's *high* faces (side 1 of its axis): the
//! neighbouring cell sees that face as a low face and never puts an edge there, so each segment is
//! an edge of exactly one triangle on each side, and no other edge is shared across a face. The
//! few loops with no such triangulation (9-point loops about a corner, 54 of the 16,384 cases) are
//! fanned about an extra vertex at their centroid (n triangles), a vertex of that cell alone. So the
//! surface of a volume is closed wherever no NaN stops it. Triangles wind counter-clockwise seen
//! from the above side (their right-hand normal points towards increasing
//! values).

use std::sync::OnceLock;

/// The 12 cube edges as (lower corner, direction bit).
pub(crate) const EDGES: [(u8, u8); 12] = {
    let mut e = [(0u8, 0u8); 12];
    let mut n = 0;
    let mut d = 1u8;
    while d <= 4 {
        let mut lo = 0u8;
        while lo < 8 {
            if lo & d == 0 {
                e[n] = (lo, d);
                n += 1;
            }
            lo += 1;
        }
        d <<= 1;
    }
    e
};

/// Generated tables: triangles of case `mask | bits << 8` are `tris[start[i]..start[i + 1]]`, as
/// edge ids into [`EDGES`]; `ambiguous[mask]` has bit `f` set when face `f` is ambiguous.
pub(crate) struct Cases {
    pub(crate) start: Vec<u32>,
    pub(crate) tris: Vec<[u8; 3]>,
    pub(crate) ambiguous: [u8; 256],
    /// Cases with a loop that has no triangulation without a diagonal in a low face (see
    /// `build`): it is fanned about an extra vertex at its centroid.
    pub(crate) has_centre: Vec<bool>,
    /// (case, loop) of those loops, in case order; in a triangle, id `CENTRE + k` is the centroid
    /// of the case's `k`-th such loop.
    pub(crate) centre_loops: Vec<(usize, Vec<u8>)>,
}

/// Triangle corner ids from here on are loop centroids (see [`Cases::centre_loops`]).
pub(crate) const CENTRE: u8 = 12;

impl Cases {
    /// The centroid loops of case `case` (empty for almost every case).
    pub(crate) fn centres(&self, case: usize) -> impl Iterator<Item = &[u8]> {
        let lo = self.centre_loops.partition_point(|(i, _)| *i < case);
        self.centre_loops[lo..].iter().take_while(move |(i, _)| *i == case).map(|(_, l)| l.as_slice())
    }
}

pub(crate) fn cases() -> &'static Cases {
    static T: OnceLock<Cases> = OnceLock::new();
    T.get_or_init(build)
}

/// Face `f = 2 * axis + side`: its corners in cyclic order `q0..q3` (q0 the lowest; q1 = q0 + the
/// lower other axis). The same four samples in the same order from both cells sharing the face.
pub(crate) const fn face_corners(f: usize) -> [u8; 4] {
    let a = f / 2;
    let s = (f % 2) as u8;
    let (u, v) = match a {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let q0 = s << a;
    [q0, q0 | 1 << u, q0 | 1 << u | 1 << v, q0 | 1 << v]
}

/// The face decider: the face's centre counts as above when the mean of its four samples (in the
/// face's own corner order, f64) is >= w. Depends on the face's samples only: both cells agree.
#[inline]
pub(crate) fn face_centre_above(q: [f32; 4], w: f32) -> bool {
    (q[0] as f64 + q[1] as f64 + q[2] as f64 + q[3] as f64) * 0.25 >= w as f64
}

fn edge_id(a: u8, b: u8) -> u8 {
    let (lo, d) = (a.min(b), a ^ b);
    EDGES.iter().position(|&e| e == (lo, d)).expect("adjacent corners") as u8
}

fn pos(c: u8) -> [f64; 3] {
    [(c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64]
}

fn mid(e: u8) -> [f64; 3] {
    let (lo, d) = EDGES[e as usize];
    let (a, b) = (pos(lo), pos(lo | d));
    [0, 1, 2].map(|i| 0.5 * (a[i] + b[i]))
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// True when two edges lie on a common face of the cube; with `low_only`, on a common *low* face
/// (side 0 of its axis).
fn share_face(e1: u8, e2: u8, low_only: bool) -> bool {
    let ((l1, d1), (l2, d2)) = (EDGES[e1 as usize], EDGES[e2 as usize]);
    (0..3).any(|a| {
        let bit = 1u8 << a;
        d1 != bit && d2 != bit && (l1 & bit) == (l2 & bit) && !(low_only && l1 & bit != 0)
    })
}

/// The directed contour segments of one face.
fn face_segments(f: usize, mask: usize, centre_above: bool, out: &mut Vec<(u8, u8)>) {
    let q = face_corners(f);
    let above = q.map(|c| (mask >> c) & 1 == 1);
    let crossing: Vec<usize> = (0..4).filter(|&k| above[k] != above[(k + 1) % 4]).collect();
    let axis = f / 2;
    let mut n = [0.0; 3];
    n[axis] = if f % 2 == 1 { 1.0 } else { -1.0 };
    let edge = |k: usize| edge_id(q[k], q[(k + 1) % 4]);
    let centre = {
        let p = q.map(pos);
        [0, 1, 2].map(|i| 0.25 * (p[0][i] + p[1][i] + p[2][i] + p[3][i]))
    };
    // (segment, a point on its above side)
    let mut segs: Vec<((u8, u8), [f64; 3])> = Vec::new();
    match crossing.len() {
        0 => {}
        2 => {
            let k = (0..4).find(|&k| above[k]).unwrap();
            segs.push(((edge(crossing[0]), edge(crossing[1])), pos(q[k])));
        }
        4 => {
            // Cut off the corners on the side the centre is not on.
            for k in 0..4 {
                if above[k] != centre_above {
                    let s = (edge((k + 3) % 4), edge(k));
                    segs.push((s, if above[k] { pos(q[k]) } else { centre }));
                }
            }
        }
        _ => unreachable!("a closed cycle of 4 corners changes sign an even number of times"),
    }
    for ((a, b), r) in segs {
        let (pa, pb) = (mid(a), mid(b));
        let left = dot(cross(n, sub(pb, pa)), sub(r, pa));
        debug_assert!(left.abs() > 1e-9);
        out.push(if left > 0.0 { (a, b) } else { (b, a) });
    }
}

/// A triangulation of the polygon `lp` (edge ids) whose diagonals never join two points of one
/// face (with `allow_high`: of one low face), by an interval dynamic programme, or `None`.
fn triangulate(lp: &[u8], allow_high: bool) -> Option<Vec<[u8; 3]>> {
    let n = lp.len();
    // ok[i][j]: the sub-polygon i..=j (chord i-j) can be triangulated.
    let chord_ok = |i: usize, j: usize| j == i + 1 || (i == 0 && j == n - 1) || !share_face(lp[i], lp[j], allow_high);
    let mut best: Vec<Vec<Option<usize>>> = vec![vec![None; n]; n];
    let mut ok = vec![vec![false; n]; n];
    for i in 0..n - 1 {
        ok[i][i + 1] = true;
    }
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            if !chord_ok(i, j) {
                continue;
            }
            // Prefer the apex nearest the middle (fewer slivers).
            let mut ks: Vec<usize> = (i + 1..j).collect();
            ks.sort_by_key(|&k| (2 * k).abs_diff(i + j));
            if let Some(&k) = ks.iter().find(|&&k| ok[i][k] && ok[k][j]) {
                ok[i][j] = true;
                best[i][j] = Some(k);
            }
        }
    }
    if !ok[0][n - 1] {
        return None;
    }
    let mut out = Vec::new();
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let k = best[i][j].unwrap();
        out.push([lp[i], lp[k], lp[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
    Some(out)
}

fn build() -> Cases {
    let mut start = Vec::with_capacity(256 * 64 + 1);
    let mut tris = Vec::new();
    let mut ambiguous = [0u8; 256];
    let mut centre_loops: Vec<(usize, Vec<u8>)> = Vec::new();
    for (mask, amb) in ambiguous.iter_mut().enumerate() {
        for f in 0..6 {
            let above = face_corners(f).map(|c| (mask >> c) & 1 == 1);
            if above[0] == above[2] && above[1] == above[3] && above[0] != above[1] {
                *amb |= 1 << f;
            }
        }
    }
    for idx in 0..256 * 64 {
        start.push(tris.len() as u32);
        let (mask, bits) = (idx & 255, idx >> 8);
        let mut segs = Vec::new();
        for f in 0..6 {
            face_segments(f, mask, (bits >> f) & 1 == 1, &mut segs);
        }
        let mut next = [u8::MAX; 12];
        for &(a, b) in &segs {
            assert_eq!(next[a as usize], u8::MAX, "edge {a} starts two segments (case {idx})");
            next[a as usize] = b;
        }
        let mut seen = [false; 12];
        for &(a0, _) in &segs {
            if seen[a0 as usize] {
                continue;
            }
            let mut lp = Vec::new();
            let mut a = a0;
            while !seen[a as usize] {
                seen[a as usize] = true;
                lp.push(a);
                a = next[a as usize];
                assert_ne!(a, u8::MAX, "open contour (case {idx})");
            }
            assert_eq!(a, a0, "contour loops must close (case {idx})");
            match triangulate(&lp, false).or_else(|| triangulate(&lp, true)) {
                Some(t) => tris.extend(t),
                None => {
                    // A fan about a vertex of the cell's own at the loop's centroid (id CENTRE + k).
                    let c = CENTRE + centre_loops.iter().filter(|(i, _)| *i == idx).count() as u8;
                    tris.extend((0..lp.len()).map(|k| [c, lp[k], lp[(k + 1) % lp.len()]]));
                    centre_loops.push((idx, lp.clone()));
                }
            }
        }
    }
    start.push(tris.len() as u32);
    let mut has_centre = vec![false; 256 * 64];
    for (i, _) in &centre_loops {
        has_centre[*i] = true;
    }
    // Orientation: with the above side on the left of every segment seen from outside, the loops
    // run counter-clockwise seen from the above side, and so do their triangles (checked in the
    // tests for every one-corner case).
    Cases { start, tris, ambiguous, has_centre, centre_loops }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case(mask: usize, bits: usize) -> &'static [[u8; 3]] {
        let c = cases();
        let i = mask | bits << 8;
        &c.tris[c.start[i] as usize..c.start[i + 1] as usize]
    }

    #[test]
    fn edges_and_faces() {
        assert_eq!(EDGES.len(), 12);
        assert!(EDGES.iter().all(|&(lo, d)| lo & d == 0 && d.count_ones() == 1));
        for f in 0..6 {
            let q = face_corners(f);
            for k in 0..4 {
                assert_eq!((q[k] ^ q[(k + 1) % 4]).count_ones(), 1);
            }
            // the opposite face is the same square shifted along the axis
            if f % 2 == 0 {
                assert_eq!(face_corners(f + 1), q.map(|c| c | 1 << (f / 2)));
            }
        }
    }

    #[test]
    fn every_case_uses_its_crossing_edges() {
        let c = cases();
        // rare: 9-point loops about a corner, fanned about their centroid
        assert!(!c.centre_loops.is_empty() && c.centre_loops.len() < 100, "{}", c.centre_loops.len());
        assert!(c.centre_loops.iter().all(|(_, l)| l.len() >= 7));
        assert!(case(0, 0).is_empty() && case(255, 0).is_empty());
        // classic counts: one corner -> 1 triangle, an edge's two corners -> 2 (a quad)
        assert_eq!(case(1, 0).len(), 1);
        assert_eq!(case(3, 0).len(), 2);
        // two corners on a face diagonal: separated (2 triangles) or joined (a tube, 4)
        assert_eq!(case(0b1001, 0).len(), 2);
        let f = (0..6).find(|&f| c.ambiguous[0b1001] >> f & 1 == 1).unwrap();
        assert_eq!(case(0b1001, 1 << f).len(), 4);
        for i in 0..256 * 64 {
            let t = &c.tris[c.start[i] as usize..c.start[i + 1] as usize];
            assert!(t.len() <= 12);
            // every crossing edge is used, no other
            let mask = i & 255;
            let mut used: Vec<u8> = t.iter().flatten().copied().filter(|&e| e < CENTRE).collect();
            used.sort();
            used.dedup();
            let crossing: Vec<u8> = (0..12u8)
                .filter(|&e| {
                    let (lo, d) = EDGES[e as usize];
                    (mask >> lo) & 1 != (mask >> (lo | d)) & 1
                })
                .collect();
            assert_eq!(used, crossing, "case {i}");
        }
    }

    #[test]
    fn triangles_face_the_above_side() {
        for corner in 0..8u8 {
            for (mask, sign) in [(1usize << corner, 1.0), (255 ^ (1usize << corner), -1.0)] {
                for t in case(mask, 0) {
                    let p = t.map(mid);
                    let nrm = cross(sub(p[1], p[0]), sub(p[2], p[0]));
                    let toward = sub(pos(corner), p[0]);
                    assert!(sign * dot(nrm, toward) > 0.0, "mask {mask}");
                }
            }
        }
    }

    #[test]
    fn face_decider_is_symmetric_in_its_samples() {
        // the same four values give the same answer whichever cell reads them
        let q = [0.3f32, -0.2, 0.25, -0.4];
        assert!(face_centre_above(q, -0.02) && !face_centre_above(q, 0.0));
    }
}

//! Levels 1.. of a block by cell merging (Jia et al.): a quadtree over the block's (i, j)
//! columns, a node of height h covering 2^h x 2^h columns in every layer.
//!
//! Level h is made from level h - 1 node by node. For each parent node, layer and face
//! direction, the *group* is the faces that cover the parent's side in that direction: for the
//! top and bottom, the single faces covering each child's top (bottom); for a lateral side, those
//! of the children along that side. A group merges when every child along the side has one
//! whole face, all of one region (never across regions; faults and inactive cells cut faces into
//! pieces or leave children without a face, so nothing merges across them), the side is not on
//! a seam with another block (seams are kept at full resolution at every level, so that
//! neighbouring blocks at any levels meet exactly; the grid's own outline merges like the inside), and no vertex inside the group's outline is used by a face outside
//! the group (no T-junction). The merged face is the group's outline with every vertex removed
//! that is not one of the parent's corners, not on a seam, and used by exactly two
//! faces, both merged faces that remove it along the same two edges (so the edge u-v-w becomes
//! u-w on both sides). A group whose reduced outline would be concave, or which would move the
//! surface by more than the faces' tolerance (half the cell size across the face: a layer's top
//! and base cannot cross), stays as its previous faces; the decision is repeated until stable.
//! The level's error is the previous level's plus the largest distance of a removed vertex from
//! the merged face (from the segment that replaced it, for outline vertices; from the face's
//! plane, for inner ones).

use super::faces::{Block, Face};
use super::poly::{convex, newell, triangulate, FastMap, Verts};

/// Node key at some height: (node i, node j, layer, direction).
type Key = (u32, u32, u32, u8);

/// One level's faces and the faces covering a whole node side.
pub(crate) struct LevelFaces {
    pub faces: Vec<Face>,
    pub nodes: FastMap<Key, u32>,
    pub error: f64,
}

/// Level 0's node map: every whole face, keyed by its cell.
pub(crate) fn level0(faces: Vec<Face>, b: Block) -> LevelFaces {
    let mut nodes = FastMap::default();
    for (f, face) in faces.iter().enumerate() {
        if face.whole {
            nodes.insert(
                ((face.ci as usize - b.i0) as u32, (face.cj as usize - b.j0) as u32, face.k, face.dir),
                f as u32,
            );
        }
    }
    LevelFaces { faces, nodes, error: 0.0 }
}

struct Group {
    key: Key,
    members: Vec<u32>,
    outline: Vec<u32>,
    inner: Vec<u32>,
    /// Pillar ids that are the parent side's corners.
    corner_pillars: Vec<u32>,
}

/// Level h (>= 1) from level h - 1.
pub(crate) fn next_level(
    prev: &LevelFaces,
    h: u32,
    b: Block,
    (ni, nj): (usize, usize),
    verts: &mut Verts,
) -> LevelFaces {
    let (bw, bh) = ((b.i1 - b.i0) as u32, (b.j1 - b.j0) as u32);
    let nodes_at = |n: u32, hh: u32| n.div_ceil(1 << hh);
    let (cw, ch) = (nodes_at(bw, h - 1), nodes_at(bh, h - 1));
    let (pw, ph) = (nodes_at(bw, h), nodes_at(bh, h));
    let nv = verts.len();
    let mut use_count = vec![0u32; nv];
    for f in &prev.faces {
        for &v in &f.verts {
            use_count[v as usize] += 1;
        }
    }
    let pillar_id = |pi: u32, pj: u32| pj * (ni as u32 + 1) + pi;
    // Parent keys with at least one child face, in a fixed order.
    let mut parents: Vec<Key> = prev.nodes.keys().map(|&(i, j, k, d)| (i / 2, j / 2, k, d)).collect();
    parents.sort_unstable();
    parents.dedup();
    let mut groups: Vec<Group> = Vec::new();
    let mut carried: Vec<(Key, u32)> = Vec::new();
    for &key in &parents {
        let (pi, pj, k, d) = key;
        let xs: Vec<u32> = (2 * pi..(2 * pi + 2).min(cw)).collect();
        let ys: Vec<u32> = (2 * pj..(2 * pj + 2).min(ch)).collect();
        // The parent's column and pillar range (global).
        let ia = b.i0 as u32 + (pi << h);
        let ib = (b.i0 as u32 + ((pi + 1) << h)).min(b.i1 as u32);
        let ja = b.j0 as u32 + (pj << h);
        let jb = (b.j0 as u32 + ((pj + 1) << h)).min(b.j1 as u32);
        let (children, border, corner_pillars): (Vec<(u32, u32)>, bool, Vec<u32>) = match d {
            0 => (
                ys.iter().map(|&y| (xs[0], y)).collect(),
                pi == 0 && b.seam_i(b.i0, ni),
                vec![pillar_id(ia, ja), pillar_id(ia, jb)],
            ),
            1 => (
                ys.iter().map(|&y| (*xs.last().unwrap_or(&0), y)).collect(),
                pi + 1 == pw && b.seam_i(b.i1, ni),
                vec![pillar_id(ib, ja), pillar_id(ib, jb)],
            ),
            2 => (
                xs.iter().map(|&x| (x, ys[0])).collect(),
                pj == 0 && b.seam_j(b.j0, nj),
                vec![pillar_id(ia, ja), pillar_id(ib, ja)],
            ),
            3 => (
                xs.iter().map(|&x| (x, *ys.last().unwrap_or(&0))).collect(),
                pj + 1 == ph && b.seam_j(b.j1, nj),
                vec![pillar_id(ia, jb), pillar_id(ib, jb)],
            ),
            _ => (
                ys.iter().flat_map(|&y| xs.iter().map(move |&x| (x, y))).collect(),
                false,
                vec![pillar_id(ia, ja), pillar_id(ib, ja), pillar_id(ia, jb), pillar_id(ib, jb)],
            ),
        };
        let members: Option<Vec<u32>> = children.iter().map(|&(x, y)| prev.nodes.get(&(x, y, k, d)).copied()).collect();
        let Some(members) = members else { continue };
        if members.len() == 1 {
            carried.push((key, members[0]));
            continue;
        }
        if border {
            continue;
        }
        let region = prev.faces[members[0] as usize].region;
        if members.iter().any(|&m| prev.faces[m as usize].region != region) {
            continue;
        }
        if let Some((outline, inner)) = outline_of(&members, &prev.faces) {
            // Inner vertices must be used by the group's faces only.
            let free = inner.iter().all(|&v| {
                let in_group = members.iter().filter(|&&m| prev.faces[m as usize].verts.contains(&v)).count() as u32;
                use_count[v as usize] == in_group
            });
            if free {
                groups.push(Group { key, members, outline, inner, corner_pillars });
            }
        }
    }
    // Accept groups until the vertex removals are consistent and every reduced face is convex
    // and within tolerance.
    let mut accepted = vec![true; groups.len()];
    let mut drop = vec![false; nv];
    loop {
        let mut claims = vec![0u8; nv];
        let mut nb: FastMap<u32, (u32, u32)> = FastMap::default();
        let mut pair_ok = vec![true; nv];
        let mut new_use = use_count.clone();
        for (g, grp) in groups.iter().enumerate() {
            if !accepted[g] {
                continue;
            }
            for &m in &grp.members {
                for &v in &prev.faces[m as usize].verts {
                    new_use[v as usize] -= 1;
                }
            }
            let n = grp.outline.len();
            for w in 0..n {
                let v = grp.outline[w];
                new_use[v as usize] += 1;
                let vi = v as usize;
                if verts.border[vi] || grp.corner_pillars.contains(&verts.pillar[vi]) {
                    continue;
                }
                let (u, x) = (grp.outline[(w + n - 1) % n], grp.outline[(w + 1) % n]);
                claims[vi] = claims[vi].saturating_add(1);
                match nb.get(&v) {
                    None => {
                        nb.insert(v, (u, x));
                    }
                    Some(&(a, c)) => pair_ok[vi] &= (a, c) == (x, u),
                }
            }
        }
        for v in 0..nv {
            drop[v] = claims[v] == 2 && new_use[v] == 2 && pair_ok[v];
        }
        let mut changed = false;
        for (g, grp) in groups.iter().enumerate() {
            if !accepted[g] {
                continue;
            }
            let reduced: Vec<u32> = grp.outline.iter().copied().filter(|&v| !drop[v as usize]).collect();
            let tol = grp.members.iter().map(|&m| prev.faces[m as usize].tol).fold(f64::INFINITY, f64::min);
            let ok = reduced.len() >= 3 && convex(&reduced, verts) && removal_error(grp, &reduced, &drop, verts) <= tol;
            if !ok {
                accepted[g] = false;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    // The new level: untouched faces, then merged ones.
    let mut in_group = vec![false; prev.faces.len()];
    let mut err = 0.0f64;
    for (g, grp) in groups.iter().enumerate() {
        if accepted[g] {
            for &m in &grp.members {
                in_group[m as usize] = true;
            }
        }
    }
    let mut faces: Vec<Face> = Vec::with_capacity(prev.faces.len());
    let mut remap = vec![u32::MAX; prev.faces.len()];
    for (f, face) in prev.faces.iter().enumerate() {
        if !in_group[f] {
            remap[f] = faces.len() as u32;
            faces.push(Face {
                verts: face.verts.clone(),
                tris: face.tris.clone(),
                dir: face.dir,
                k: face.k,
                ci: face.ci,
                cj: face.cj,
                region: face.region,
                value: face.value,
                whole: face.whole,
                tol: face.tol,
                kind: face.kind,
            });
        }
    }
    let mut nodes: FastMap<Key, u32> = FastMap::default();
    for (key, f) in carried {
        if remap[f as usize] != u32::MAX {
            nodes.insert(key, remap[f as usize]);
        }
    }
    for (g, grp) in groups.iter().enumerate() {
        if !accepted[g] {
            continue;
        }
        let reduced: Vec<u32> = grp.outline.iter().copied().filter(|&v| !drop[v as usize]).collect();
        err = err.max(removal_error(grp, &reduced, &drop, verts));
        let first = &prev.faces[grp.members[0] as usize];
        let vals: Vec<f64> =
            grp.members.iter().map(|&m| prev.faces[m as usize].value).filter(|v| !v.is_nan()).collect();
        let value = if vals.is_empty() { f64::NAN } else { vals.iter().sum::<f64>() / vals.len() as f64 };
        let tol = grp.members.iter().map(|&m| prev.faces[m as usize].tol).fold(f64::INFINITY, f64::min);
        let mut tris = Vec::with_capacity(reduced.len());
        triangulate(&reduced, verts, first.region, &mut tris);
        nodes.insert(grp.key, faces.len() as u32);
        faces.push(Face {
            verts: reduced,
            tris,
            dir: first.dir,
            k: first.k,
            ci: b.i0 as u32 + (grp.key.0 << h),
            cj: b.j0 as u32 + (grp.key.1 << h),
            region: first.region,
            value,
            whole: true,
            tol,
            kind: first.kind,
        });
    }
    LevelFaces { faces, nodes, error: prev.error + err }
}

/// The outline of a group of faces (their union's boundary: edges not shared within the group)
/// as one ring, and the vertices inside it; None unless the union is one simple ring.
fn outline_of(members: &[u32], faces: &[Face]) -> Option<(Vec<u32>, Vec<u32>)> {
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for &m in members {
        let p = &faces[m as usize].verts;
        for w in 0..p.len() {
            edges.push((p[w], p[(w + 1) % p.len()]));
        }
    }
    let mut keep = vec![true; edges.len()];
    for a in 0..edges.len() {
        if !keep[a] {
            continue;
        }
        if let Some(b) = (0..edges.len()).find(|&b| keep[b] && edges[b] == (edges[a].1, edges[a].0)) {
            keep[a] = false;
            keep[b] = false;
        }
    }
    let rest: Vec<(u32, u32)> = edges.iter().zip(&keep).filter(|(_, &k)| k).map(|(e, _)| *e).collect();
    if rest.len() < 3 {
        return None;
    }
    let mut ring = vec![rest[0].0];
    let mut cur = rest[0].1;
    while cur != rest[0].0 {
        if ring.len() > rest.len() {
            return None;
        }
        let mut next = rest.iter().filter(|e| e.0 == cur);
        let e = next.next()?;
        if next.next().is_some() {
            return None;
        }
        ring.push(cur);
        cur = e.1;
    }
    if ring.len() != rest.len() {
        return None;
    }
    let mut inner: Vec<u32> = Vec::new();
    for &m in members {
        for &v in &faces[m as usize].verts {
            if !ring.contains(&v) && !inner.contains(&v) {
                inner.push(v);
            }
        }
    }
    Some((ring, inner))
}

/// The largest distance of a vertex the merge removes from the merged face: outline vertices
/// from the segment between the kept vertices around them, inner vertices from the face's plane.
fn removal_error(grp: &Group, reduced: &[u32], drop: &[bool], verts: &Verts) -> f64 {
    let mut err = 0.0f64;
    if reduced.len() >= 3 {
        let n = newell(reduced, verts).normalize_or_zero();
        let mut c = glam::DVec3::ZERO;
        for &v in reduced {
            c += verts.p(v);
        }
        c /= reduced.len() as f64;
        for &v in &grp.inner {
            err = err.max((verts.p(v) - c).dot(n).abs());
        }
    }
    let o = &grp.outline;
    let m = o.len();
    for w in 0..m {
        if !drop[o[w] as usize] {
            continue;
        }
        let mut a = (w + m - 1) % m;
        while drop[o[a] as usize] && a != w {
            a = (a + m - 1) % m;
        }
        let mut c = (w + 1) % m;
        while drop[o[c] as usize] && c != w {
            c = (c + 1) % m;
        }
        let (pa, pc, pv) = (verts.p(o[a]), verts.p(o[c]), verts.p(o[w]));
        let ab = pc - pa;
        let t = if ab.length_squared() > 0.0 { ((pv - pa).dot(ab) / ab.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
        err = err.max((pa + t * ab - pv).length());
    }
    err
}

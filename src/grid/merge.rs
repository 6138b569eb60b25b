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
//!
//! Faults: the pieces a fault cuts faces into are no node's side, but they lie in the fault's
//! interfaces, so they merge by their own groups ([`fault_groups`]): per interface, side, region
//! and 2^h rows along it, each connected set of pieces whose union is one ring becomes one
//! *strip* (all the layers of a region over whatever lies across, at once), taking part in the
//! same vertex removals. A strip need not be convex (an inactive cell beside the fault notches
//! it): it is then triangulated by ear clipping. A union with a hole (an inactive cell inside
//! the rows) stays as the strips of the level below.

use super::faces::{kind, Block, Face};
use super::poly::{convex, ear_clip, newell, removed_spans, triangulate, FastMap, Verts, STRAIGHT};

/// Node key at some height: (node i, node j, layer, direction).
type Key = (u32, u32, u32, u8);

/// One level's faces and the faces covering a whole node side.
pub(crate) struct LevelFaces {
    pub faces: Vec<Face>,
    pub nodes: FastMap<Key, u32>,
    pub error: f64,
    /// The largest chord between a face's unit normal and the normal of a level-0 triangle it
    /// covers (bounded by summing each level's chord to its members' triangles): how far facet
    /// shading may change (`lod::levels::Level::shading_error`).
    pub shading: f64,
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
    LevelFaces { faces, nodes, error: 0.0, shading: 0.0 }
}

struct Group {
    key: Key,
    members: Vec<u32>,
    outline: Vec<u32>,
    inner: Vec<u32>,
    /// Pillar ids that are the parent side's corners.
    corner_pillars: Vec<u32>,
    /// A strip of fault pieces (see [`fault_groups`]): not a node side.
    fault: bool,
}

/// What the stages of [`next_level`] read: the level below, the height made, the block, and
/// whether the grid is coloured per cell.
#[derive(Clone, Copy)]
struct Step<'a> {
    prev: &'a LevelFaces,
    h: u32,
    b: Block,
    cells: bool,
}

/// Level h (>= 1) from level h - 1.
pub(crate) fn next_level(
    prev: &LevelFaces,
    h: u32,
    b: Block,
    (ni, nj): (usize, usize),
    cells: bool,
    verts: &mut Verts,
) -> LevelFaces {
    let s = Step { prev, h, b, cells };
    let nv = verts.len();
    let mut use_count = vec![0u32; nv];
    for f in &prev.faces {
        for &v in &f.verts {
            use_count[v as usize] += 1;
        }
    }
    let (mut groups, carried) = node_groups(s, (ni, nj), &use_count, verts);
    fault_groups(prev, h, b, (ni, nj), &use_count, verts, &mut groups);
    if cells {
        // Strips are coloured flat (`cells::FLAT`): only pieces of one value merge.
        groups.retain(|g| !g.fault || super::cells::strip_ok(&g.members, &prev.faces));
    }
    let (accepted, drop) = accept_groups(s, &groups, &use_count, verts);
    // The new level: untouched faces, then merged ones.
    let (mut err, mut shade) = (0.0f64, 0.0f64);
    let (mut faces, remap) = untouched_faces(prev, &groups, &accepted);
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
        let face = merged_face(s, grp, &drop, verts, (&mut err, &mut shade));
        if !grp.fault {
            nodes.insert(grp.key, faces.len() as u32);
        }
        faces.push(face);
    }
    LevelFaces { faces, nodes, error: prev.error + err, shading: prev.shading + shade }
}

/// The groups of whole faces covering a parent node's side that may merge (every child along
/// the side has one, all of one region, not on a seam, no T-junction), and the node sides
/// carried over as one face (a single child).
fn node_groups(
    s: Step<'_>,
    (ni, nj): (usize, usize),
    use_count: &[u32],
    verts: &Verts,
) -> (Vec<Group>, Vec<(Key, u32)>) {
    let Step { prev, h, b, .. } = s;
    let (bw, bh) = ((b.i1 - b.i0) as u32, (b.j1 - b.j0) as u32);
    let nodes_at = |n: u32, hh: u32| n.div_ceil(1 << hh);
    let (cw, ch) = (nodes_at(bw, h - 1), nodes_at(bh, h - 1));
    let (pw, ph) = (nodes_at(bw, h), nodes_at(bh, h));
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
            if free(&members, &inner, &prev.faces, use_count, verts) {
                groups.push(Group { key, members, outline, inner, corner_pillars, fault: false });
            }
        }
    }
    (groups, carried)
}

/// Accepts groups until the vertex removals are consistent and every reduced face is convex
/// and within tolerance. Returns per group whether it merges, and per vertex whether it is
/// removed.
fn accept_groups(s: Step<'_>, groups: &[Group], use_count: &[u32], verts: &Verts) -> (Vec<bool>, Vec<bool>) {
    let Step { prev, cells, .. } = s;
    let nv = use_count.len();
    let mut accepted = vec![true; groups.len()];
    let mut drop = vec![false; nv];
    // Per group: the reduced outline last checked (a fingerprint) and whether its shape passed
    // (ear clipping a long strip is the costly part; most outlines do not change between rounds).
    let mut shape_seen: Vec<Option<(u64, bool)>> = vec![None; groups.len()];
    loop {
        removals(prev, groups, &accepted, use_count, verts, &mut drop);
        let mut changed = false;
        for (g, grp) in groups.iter().enumerate() {
            if !accepted[g] {
                continue;
            }
            let reduced: Vec<u32> = grp.outline.iter().copied().filter(|&v| !drop[v as usize]).collect();
            let tol = grp.members.iter().map(|&m| prev.faces[m as usize].tol).fold(f64::INFINITY, f64::min);
            let print = reduced
                .iter()
                .fold(reduced.len() as u64, |h, &v| (h.rotate_left(7) ^ v as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
            let shape_ok = match shape_seen[g] {
                Some((p, ok)) if p == print => ok,
                _ => {
                    let ok = reduced.len() >= 3
                        && (convex(&reduced, verts) || (grp.fault && ear_clip(&reduced, verts).is_some()))
                        && (!cells || grp.fault || super::cells::exact_shape(&reduced, verts));
                    shape_seen[g] = Some((print, ok));
                    ok
                }
            };
            let ok = shape_ok && removal_error(grp, &reduced, &drop, verts) <= tol;
            if !ok {
                accepted[g] = false;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    (accepted, drop)
}

/// The vertices the accepted groups remove (into `drop`): claimed by exactly two of them along
/// the same two edges, used by those two faces only after merging, and not a corner.
fn removals(
    prev: &LevelFaces,
    groups: &[Group],
    accepted: &[bool],
    use_count: &[u32],
    verts: &Verts,
    drop: &mut [bool],
) {
    let nv = use_count.len();
    let mut claims = vec![0u8; nv];
    let mut nb: FastMap<u32, (u32, u32)> = FastMap::default();
    let mut pair_ok = vec![true; nv];
    let mut new_use = use_count.to_vec();
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
            // A strip removes only vertices on straight stretches of its outline (its corners,
            // where the pieces' lines meet, are no node's corners).
            if grp.fault {
                let (e1, e2) = (verts.p(v) - verts.p(u), verts.p(x) - verts.p(v));
                if e1.cross(e2).length() > STRAIGHT * e1.length() * e2.length() {
                    continue;
                }
            }
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
}

/// The faces of `prev` in no accepted group, copied in order, and each face's index among them
/// (`u32::MAX` for merged ones).
fn untouched_faces(prev: &LevelFaces, groups: &[Group], accepted: &[bool]) -> (Vec<Face>, Vec<u32>) {
    let mut in_group = vec![false; prev.faces.len()];
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
                lat: face.lat.clone(),
            });
        }
    }
    (faces, remap)
}

/// The merged face of the accepted group `grp` (its outline less the `drop`ped vertices),
/// raising the level's error and shading chord (`err`, `shade`) by its own.
fn merged_face(s: Step<'_>, grp: &Group, drop: &[bool], verts: &mut Verts, (err, shade): (&mut f64, &mut f64)) -> Face {
    let Step { prev, h, b, cells } = s;
    let reduced: Vec<u32> = grp.outline.iter().copied().filter(|&v| !drop[v as usize]).collect();
    *err = err.max(removal_error(grp, &reduced, drop, verts));
    *shade = shade.max(normal_chord(&reduced, &grp.members, &prev.faces, verts));
    let first = &prev.faces[grp.members[0] as usize];
    // The members' cell coordinates of a vertex (they agree: see `cells`).
    let lat_of = |v: u32| grp.members.iter().find_map(|&m| super::cells::of(&prev.faces[m as usize], v));
    if cells && !grp.fault {
        // Colours move with the lattice's map on the face: that is part of the error too.
        *err = err.max(super::cells::drift(first.dir, &grp.outline, &grp.inner, &reduced, drop, verts, &lat_of));
    }
    let vals: Vec<f64> = grp.members.iter().map(|&m| prev.faces[m as usize].value).filter(|v| !v.is_nan()).collect();
    let value = if vals.is_empty() { f64::NAN } else { vals.iter().sum::<f64>() / vals.len() as f64 };
    let tol = grp.members.iter().map(|&m| prev.faces[m as usize].tol).fold(f64::INFINITY, f64::min);
    let mut tris = Vec::with_capacity(reduced.len());
    match (convex(&reduced, verts), ear_clip(&reduced, verts)) {
        (false, Some(t)) => tris = t,
        _ => triangulate(&reduced, verts, first.region, &mut tris),
    }
    let (ci, cj, k) = if grp.fault {
        let m = |f: fn(&Face) -> u32| grp.members.iter().map(|&x| f(&prev.faces[x as usize])).min().unwrap_or(0);
        (m(|f| f.ci), m(|f| f.cj), m(|f| f.k))
    } else {
        (b.i0 as u32 + (grp.key.0 << h), b.j0 as u32 + (grp.key.1 << h), first.k)
    };
    let lat = match (cells, grp.fault) {
        (false, _) => Vec::new(),
        (true, true) => vec![super::cells::FLAT; reduced.len()],
        (true, false) => reduced.iter().map(|&v| lat_of(v).unwrap_or(0)).collect(),
    };
    Face {
        verts: reduced,
        tris,
        dir: first.dir,
        k,
        ci,
        cj,
        region: first.region,
        value,
        whole: !grp.fault,
        tol,
        kind: if grp.members.iter().all(|&m| prev.faces[m as usize].kind == first.kind) {
            first.kind
        } else {
            kind::MIXED
        },
        lat,
    }
}

/// The largest chord between the unit normal of the merged polygon `reduced` and those of its
/// members' triangles.
fn normal_chord(reduced: &[u32], members: &[u32], faces: &[Face], verts: &Verts) -> f64 {
    let n = newell(reduced, verts).normalize_or_zero();
    let mut chord = 0.0f64;
    for &m in members {
        for t in &faces[m as usize].tris {
            let [a, b, c] = t.map(|v| verts.p(v));
            let tn = (b - a).cross(c - a).normalize_or_zero();
            if tn != glam::DVec3::ZERO {
                chord = chord.max((tn - n).length());
            }
        }
    }
    chord
}

/// Inner vertices (of a group's faces, not on its outline) must be used by the group's faces
/// only, and none may lie on a seam.
fn free(members: &[u32], inner: &[u32], faces: &[Face], use_count: &[u32], verts: &Verts) -> bool {
    if inner.iter().any(|&v| verts.border[v as usize]) {
        return false;
    }
    let mut uses: FastMap<u32, u32> = FastMap::default();
    for &m in members {
        for &v in &faces[m as usize].verts {
            *uses.entry(v).or_insert(0) += 1;
        }
    }
    inner.iter().all(|&v| uses.get(&v).copied() == Some(use_count[v as usize]))
}

/// The outline of a group of faces (their union's boundary: edges not shared within the group)
/// as one ring, and the vertices inside it; None unless the union is one simple ring.
fn outline_of(members: &[u32], faces: &[Face]) -> Option<(Vec<u32>, Vec<u32>)> {
    // Directed edges with their multiplicity; an edge and its reverse cancel.
    let mut edges: FastMap<(u32, u32), i32> = FastMap::default();
    for &m in members {
        let p = &faces[m as usize].verts;
        for w in 0..p.len() {
            let (a, c) = (p[w], p[(w + 1) % p.len()]);
            match edges.get_mut(&(c, a)) {
                Some(n) if *n > 0 => *n -= 1,
                _ => *edges.entry((a, c)).or_insert(0) += 1,
            }
        }
    }
    let mut rest: Vec<(u32, u32)> = Vec::new();
    for (&e, &n) in &edges {
        for _ in 0..n {
            rest.push(e);
        }
    }
    if rest.len() < 3 {
        return None;
    }
    rest.sort_unstable();
    let mut next: FastMap<u32, u32> = FastMap::default();
    for &(a, c) in &rest {
        if next.insert(a, c).is_some() {
            return None;
        }
    }
    let start = rest[0].0;
    let mut ring = vec![start];
    let mut cur = *next.get(&start)?;
    while cur != start {
        if ring.len() > rest.len() {
            return None;
        }
        ring.push(cur);
        cur = *next.get(&cur)?;
    }
    if ring.len() != rest.len() {
        return None;
    }
    let on_ring: FastMap<u32, ()> = ring.iter().map(|&v| (v, ())).collect();
    let mut inner: Vec<u32> = Vec::new();
    let mut seen: FastMap<u32, ()> = FastMap::default();
    for &m in members {
        for &v in &faces[m as usize].verts {
            if !on_ring.contains_key(&v) && seen.insert(v, ()).is_none() {
                inner.push(v);
            }
        }
    }
    Some((ring, inner))
}

/// Groups of fault pieces (faces that are not whole: pieces of a face across a fault, or strips
/// of them merged at a lower level). On one interface and one side of it (the same direction and
/// column line), of one region, and within one node's rows along the interface (2^h rows), each
/// connected set of pieces (sharing edges) whose union is one ring merges into one strip: the
/// pieces of a layer over the different cells across, the layers of a region above each other
/// and neighbouring rows. They lie in the interface (a ruled surface between two pillars, a
/// plane where the pillars are parallel), so the strip moves the surface only where that bends.
/// Interfaces on a seam with another block never merge (the pieces there meet faces of the
/// other block). The strips take part in the vertex removals like the node groups.
fn fault_groups(
    prev: &LevelFaces,
    h: u32,
    b: Block,
    (ni, nj): (usize, usize),
    use_count: &[u32],
    verts: &Verts,
    groups: &mut Vec<Group>,
) {
    // (direction, interface line, region, row node) -> pieces.
    let mut sets: FastMap<(u8, u32, i32, u32), Vec<u32>> = FastMap::default();
    for (f, face) in prev.faces.iter().enumerate() {
        if face.whole || face.dir >= 4 {
            continue;
        }
        let (line, row, seam) = match face.dir {
            0 => (face.ci, face.cj - b.j0 as u32, b.seam_i(face.ci as usize, ni)),
            1 => (face.ci + 1, face.cj - b.j0 as u32, b.seam_i(face.ci as usize + 1, ni)),
            2 => (face.cj, face.ci - b.i0 as u32, b.seam_j(face.cj as usize, nj)),
            _ => (face.cj + 1, face.ci - b.i0 as u32, b.seam_j(face.cj as usize + 1, nj)),
        };
        if !seam {
            // Pieces over gaps (seen from outside) and over cells (interior) merge apart.
            let dir = face.dir | (((face.kind == kind::FAULT_GAP) as u8) << 4);
            sets.entry((dir, line, face.region, row >> h)).or_default().push(f as u32);
        }
    }
    let mut keys: Vec<_> = sets.keys().copied().collect();
    keys.sort_unstable();
    for key in keys {
        let set = &sets[&key];
        if set.len() < 2 {
            continue;
        }
        // Connected components over shared edges (union-find).
        let mut parent: Vec<usize> = (0..set.len()).collect();
        fn root(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        let mut by_edge: FastMap<(u32, u32), usize> = FastMap::default();
        for (x, &f) in set.iter().enumerate() {
            let p = &prev.faces[f as usize].verts;
            for w in 0..p.len() {
                let (a, c) = (p[w], p[(w + 1) % p.len()]);
                match by_edge.get(&(c, a)) {
                    Some(&y) => {
                        let (rx, ry) = (root(&mut parent, x), root(&mut parent, y));
                        parent[rx] = ry;
                    }
                    None => {
                        by_edge.insert((a, c), x);
                    }
                }
            }
        }
        let mut comps: FastMap<usize, Vec<u32>> = FastMap::default();
        for (x, &f) in set.iter().enumerate() {
            comps.entry(root(&mut parent, x)).or_default().push(f);
        }
        let mut comps: Vec<Vec<u32>> = comps.into_values().filter(|c| c.len() >= 2).collect();
        comps.sort_unstable();
        for members in comps {
            if let Some((outline, inner)) = outline_of(&members, &prev.faces) {
                if free(&members, &inner, &prev.faces, use_count, verts) {
                    let key = (key.1, key.3, 0, key.0 & 15);
                    groups.push(Group { key, members, outline, inner, corner_pillars: Vec::new(), fault: true });
                }
            }
        }
    }
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
    for (w, a, c) in removed_spans(o, drop) {
        let (pa, pc, pv) = (verts.p(o[a]), verts.p(o[c]), verts.p(o[w]));
        let ab = pc - pa;
        let t = if ab.length_squared() > 0.0 { ((pv - pa).dot(ab) / ab.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
        err = err.max((pa + t * ab - pv).length());
    }
    err
}

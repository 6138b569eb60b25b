//! Enclosed occluder boxes of an isosurface, for the scene pipeline's `culling = "implicit"`
//! (`crate::cull::implicit`): boxes of cells wholly on one side of the isovalue that no ray from
//! outside the volume can reach without crossing the marching-cubes surface ([`super::march`]).
//!
//! **Cells.** A cell is *Below* when its 8 samples are `< w`, *Above* when they are `> w`, NaN
//! when one is NaN, else passable ([`super::bricks::leaf_nodes`], the classes the implicit walk
//! uses). A Below cell holds no triangle and no triangle touches it (none of its edges is
//! crossed), so the whole closed cell lies on the below side of the surface; an Above cell on the
//! above side (see `super::render`'s module docs).
//!
//! **Enclosed.** For one side (say above): a flood fill over the cells that are *not* of the other
//! side's class (not Below), through shared faces, edges and corners (26 neighbours), from every
//! such cell that touches the volume's border or is NaN. An Above cell the fill never reaches is
//! *enclosed*. Why a ray from outside the volume's box to a point P of an enclosed cell c crosses
//! the surface before P: let Ω be the component of (box interior minus the surface) holding P. A
//! path inside Ω passes from cell to cell through points both cells hold, and every cell it meets
//! holds an above point of Ω, so it is not Below: Ω lies in the cells the fill would reach from c.
//! None of them touches the border or is NaN (else the fill from there would have reached c), so
//! Ω stays away from the box's faces and from the holes NaN cells cut into the surface: its
//! boundary lies on the surface, which the ray must cross to enter Ω. The below side likewise
//! (fill through cells that are not Above; Below cells never reached).
//!
//! **Boxes.** Enclosed cells of each side are merged greedily into boxes (runs along x, then
//! rows along y, then layers along z, of cells not yet taken), at most [`MAX_BOXES`] (the
//! largest kept: leaving a box out only leaves occlusion unused), each inset by [`INSET`] of a
//! cell on every face: a point of the inset box has the uninset box (enclosed cells, no surface)
//! around it within a quarter cell, so a ray reaching it has crossed the surface at least a
//! quarter cell before (the margin the renderer's f32 depth and priorities need).
//!
//! Not computed (no boxes): rotated volumes (their boxes are not axis-aligned in the world),
//! lazy volumes (samples read on demand) and volumes of more than [`MAX_CELLS`] cells.

use super::bricks::{leaf_nodes, CLASS_ABOVE, CLASS_BELOW, CLASS_NAN};
use super::Volume;
use crate::error::Result;

/// At most this many boxes per isosurface.
pub const MAX_BOXES: usize = 4096;
/// Volumes with more cells get no boxes (the fill keeps a few bytes per cell).
pub const MAX_CELLS: usize = 1 << 27;
/// Each box is inset by this fraction of a cell on every face.
pub const INSET: f64 = 0.25;

/// The bounding box of `vertices` (an isosurface's mesh), None when there are none. An eye (or a
/// ray's start on the near plane) outside it reaches the boxes of [`enclosed_boxes`] only through
/// the surface: an enclosed region Ω is bounded and its boundary lies on the surface (module
/// docs), so every point of Ω lies between two points of that boundary on any line through it,
/// hence in the convex hull of the surface's vertices' box.
pub fn mesh_bounds(vertices: &[[f64; 3]]) -> Option<([f64; 3], [f64; 3])> {
    let first = *vertices.first()?;
    Some(vertices.iter().fold((first, first), |(lo, hi), v| {
        (std::array::from_fn(|a| lo[a].min(v[a])), std::array::from_fn(|a| hi[a].max(v[a])))
    }))
}

/// A box of cells: first cell (inclusive) and last (exclusive) per axis.
type CellBox = ([usize; 3], [usize; 3]);

/// The enclosed occluder boxes of the isosurface `vol = isovalue` (the volume's units), in world
/// coordinates (the grid frame: the volume is axis-aligned), inset by [`INSET`] of a cell: every
/// ray from outside the volume's box to a point of a box crosses the surface
/// (`mesh::isosurface_mesh`'s triangles) at least [`INSET`] cells before it (module docs).
/// Empty for rotated and lazy volumes and volumes over [`MAX_CELLS`] cells. Errors name
/// `isovalue` (not finite, beyond the f32 range of the residuals).
pub fn enclosed_boxes(vol: &Volume, isovalue: f64) -> Result<Vec<([f64; 3], [f64; 3])>> {
    let w = vol.residual(isovalue, "isovalue")?;
    let cells = vol.cells();
    let n = cells.iter().product::<usize>();
    if vol.rotation != 0.0 || vol.store.is_some() || n > MAX_CELLS || vol.values.len() != vol.nx * vol.ny * vol.nz {
        return Ok(Vec::new());
    }
    let classes: Vec<u8> = leaf_nodes(&vol.values, [vol.nx, vol.ny, vol.nz], w).into_iter().map(|c| c & 3).collect();
    let mut boxes = Vec::new();
    for (side, other) in [(CLASS_ABOVE, CLASS_BELOW), (CLASS_BELOW, CLASS_ABOVE)] {
        let reached = flood(&classes, cells, other);
        let enclosed: Vec<bool> = classes.iter().zip(&reached).map(|(&c, &r)| c == side && !r).collect();
        boxes.extend(merge(&enclosed, cells));
    }
    let volume = |b: &CellBox| (0..3).map(|a| b.1[a] - b.0[a]).product::<usize>();
    if boxes.len() > MAX_BOXES {
        boxes.sort_by_key(|b| std::cmp::Reverse(volume(b)));
        boxes.truncate(MAX_BOXES);
    }
    let at = |a: usize, c: f64| vol.origin[a] + c * vol.spacing[a];
    Ok(boxes
        .iter()
        .map(|(lo, hi)| {
            (std::array::from_fn(|a| at(a, lo[a] as f64 + INSET)), std::array::from_fn(|a| at(a, hi[a] as f64 - INSET)))
        })
        .collect())
}

/// Per cell (x fastest), whether the fill reaches it: from every cell that is not `blocked` (class)
/// and touches the border or is NaN, through the cells that are not `blocked`, 26 neighbours.
fn flood(classes: &[u8], cells: [usize; 3], blocked: u8) -> Vec<bool> {
    let [cx, cy, cz] = cells;
    let mut reached = vec![false; classes.len()];
    let mut stack = Vec::new();
    let idx = |i: usize, j: usize, k: usize| (k * cy + j) * cx + i;
    for k in 0..cz {
        for j in 0..cy {
            for i in 0..cx {
                let c = idx(i, j, k);
                let border = i == 0 || j == 0 || k == 0 || i + 1 == cx || j + 1 == cy || k + 1 == cz;
                if classes[c] != blocked && (border || classes[c] == CLASS_NAN) {
                    reached[c] = true;
                    stack.push((i, j, k));
                }
            }
        }
    }
    while let Some((i, j, k)) = stack.pop() {
        for k2 in k.saturating_sub(1)..=(k + 1).min(cz - 1) {
            for j2 in j.saturating_sub(1)..=(j + 1).min(cy - 1) {
                for i2 in i.saturating_sub(1)..=(i + 1).min(cx - 1) {
                    let c = idx(i2, j2, k2);
                    if !reached[c] && classes[c] != blocked {
                        reached[c] = true;
                        stack.push((i2, j2, k2));
                    }
                }
            }
        }
    }
    reached
}

/// The cells where `inside` holds, merged greedily into disjoint boxes whose union they are: from
/// each cell not yet taken (z, y, x order), a run along x, grown along y while the whole run is
/// free, then along z while the whole rectangle is.
fn merge(inside: &[bool], cells: [usize; 3]) -> Vec<CellBox> {
    let [cx, cy, cz] = cells;
    let idx = |i: usize, j: usize, k: usize| (k * cy + j) * cx + i;
    let mut free: Vec<bool> = inside.to_vec();
    let mut out = Vec::new();
    for k in 0..cz {
        for j in 0..cy {
            for i in 0..cx {
                if !free[idx(i, j, k)] {
                    continue;
                }
                let mut i1 = i + 1;
                while i1 < cx && free[idx(i1, j, k)] {
                    i1 += 1;
                }
                let row_free = |free: &[bool], j: usize, k: usize| (i..i1).all(|a| free[idx(a, j, k)]);
                let mut j1 = j + 1;
                while j1 < cy && row_free(&free, j1, k) {
                    j1 += 1;
                }
                let mut k1 = k + 1;
                while k1 < cz && (j..j1).all(|b| row_free(&free, b, k1)) {
                    k1 += 1;
                }
                for c in k..k1 {
                    for b in j..j1 {
                        for a in i..i1 {
                            free[idx(a, b, c)] = false;
                        }
                    }
                }
                out.push(([i, j, k], [i1, j1, k1]));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inside_sphere(b: &([f64; 3], [f64; 3]), c: [f64; 3], r: f64) -> bool {
        (0..8).all(|m| {
            let p: [f64; 3] = std::array::from_fn(|a| if m >> a & 1 == 1 { b.1[a] } else { b.0[a] });
            (0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f64>().sqrt() < r
        })
    }

    #[test]
    fn a_sphere_gets_boxes_inside_it_away_from_the_border() {
        // Inside the sphere the field is below 0; negated, above: both sides are found.
        for sign in [1.0f32, -1.0] {
            let v = super::super::sphere_field(25, 0.6);
            let vals: Vec<f32> = v.values.iter().map(|x| x * sign).collect();
            let v = Volume::new(vals.into(), (25, 25, 25), v.origin, v.spacing).unwrap();
            let boxes = enclosed_boxes(&v, 0.0).unwrap();
            assert!(!boxes.is_empty() && boxes.len() < 200, "{} boxes", boxes.len());
            let mesh = super::super::mesh::isosurface_mesh(&v, &super::super::MinMaxOctree::build(&v), 0.0).unwrap();
            let (blo, bhi) = mesh_bounds(&mesh.vertices).unwrap();
            for b in &boxes {
                assert!((0..3).all(|a| b.0[a] >= blo[a] && b.1[a] <= bhi[a]));
                assert!(inside_sphere(b, [0.0; 3], 0.6), "{b:?}");
                assert!((0..3).all(|a| b.0[a] > -1.0 && b.1[a] < 1.0 && b.0[a] < b.1[a]));
            }
            // Most of the sphere's inside is covered.
            let vol: f64 = boxes.iter().map(|b| (0..3).map(|a| b.1[a] - b.0[a]).product::<f64>()).sum();
            assert!(vol > 0.2 * 4.0 / 3.0 * std::f64::consts::PI * 0.6f64.powi(3), "{vol}");
        }
    }

    #[test]
    fn a_body_cut_open_by_the_border_gets_no_boxes() {
        // Two balls below 0: one inside, one centred on the x = -1 face (open there).
        let f = |x: f64, y: f64, z: f64| {
            let a = ((x - 0.5).powi(2) + y * y + z * z).sqrt() - 0.3;
            let b = ((x + 1.0).powi(2) + y * y + z * z).sqrt() - 0.5;
            a.min(b) as f32
        };
        let h = 2.0 / 32.0;
        let v = Volume::from_fn((33, 33, 33), [-1.0; 3], [h; 3], f).unwrap();
        let boxes = enclosed_boxes(&v, 0.0).unwrap();
        assert!(!boxes.is_empty());
        for b in &boxes {
            assert!(inside_sphere(b, [0.5, 0.0, 0.0], 0.3), "{b:?}");
        }
        // The outside (above 0) touches the border everywhere: no above boxes; and NaN opens a body.
        let mut vals = v.values.to_vec();
        let centre = (16 * 33 + 16) * 33 + 24; // sample (24, 16, 16): x = 0.5, in the inner ball
        vals[centre] = f32::NAN;
        let v = Volume::new(vals.into(), (33, 33, 33), v.origin, v.spacing).unwrap();
        assert!(enclosed_boxes(&v, 0.0).unwrap().is_empty());
    }

    #[test]
    fn rotated_volumes_get_none_and_bad_isovalues_are_refused() {
        let v = super::super::sphere_field(9, 0.6).with_rotation(10.0).unwrap();
        assert!(enclosed_boxes(&v, 0.0).unwrap().is_empty());
        let e = enclosed_boxes(&v, f64::NAN).unwrap_err();
        assert!(e.to_string().contains("isovalue"), "{e}");
    }
}

//! The whole isosurface of a volume as one mesh in world coordinates: the triangles the renderer
//! draws with `culling = none` (marching cubes over every node that straddles the isovalue,
//! at the renderer's default cull depth), for export (PyVista, trimesh, a scene's `add_mesh`).
//!
//! Patches share their boundary vertices bit for bit (`super::march`), so vertices are welded by
//! their exact grid-frame position; triangles are kept as extracted (zero-area ones too: they draw
//! nothing, as in the renderer). Positions are turned into the world by the volume's rotation in f64.

use std::collections::HashMap;

use super::march::extract_nodes;
use super::octree::MinMaxOctree;
use super::Volume;
use crate::error::{ensure, Result};

/// An isosurface: world vertices, faces into them, and unit normals (towards increasing values,
/// in world axes).
#[derive(Clone, Debug, Default)]
pub struct IsoMesh {
    pub vertices: Vec<[f64; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub faces: Vec<[u32; 3]>,
}

/// The isosurface `vol = isovalue` (in the volume's units) as one welded world-space mesh.
/// `tree` must be the octree of `vol`. Errors name `isovalue` (not finite, beyond the f32 range of
/// the residuals) or `volume` (an octree of another volume).
pub fn isosurface_mesh(vol: &Volume, tree: &MinMaxOctree, isovalue: f64) -> Result<IsoMesh> {
    Ok(welded(vol, tree, isovalue)?.0)
}

/// [`isosurface_mesh`] with a second volume's values at its vertices (one per vertex, in the
/// values volume's units): `values` must lie on `vol`'s grid (the same samples per axis, origin,
/// spacing and rotation; else an error naming `values`). Each value is `values`' trilinear
/// interpolant at the vertex. Almost every vertex lies on a cell edge, where the extraction placed
/// it between the edge's two samples: there that is the interpolation between the same two samples
/// of `values` with the same weights, NaN where either is NaN, exact for a field linear along the
/// edge. The rare centre vertex of a loop fanned inside a cell (`march::centroid_vertex`, under
/// 1 %) takes the interpolant at that point, over the cell's 8 samples.
pub fn isosurface_mesh_sampled(
    vol: &Volume,
    tree: &MinMaxOctree,
    isovalue: f64,
    values: &Volume,
) -> Result<(IsoMesh, Vec<f64>)> {
    let same = |a: [f64; 3], b: [f64; 3]| a.iter().zip(&b).all(|(x, y)| x == y);
    ensure([values.nx, values.ny, values.nz] == [vol.nx, vol.ny, vol.nz], "values", || {
        format!(
            "a volume of {}x{}x{} samples; expected the isosurface's grid, {}x{}x{}",
            values.nx, values.ny, values.nz, vol.nx, vol.ny, vol.nz
        )
    })?;
    ensure(
        same(values.origin, vol.origin) && same(values.spacing, vol.spacing) && values.rotation == vol.rotation,
        "values",
        || {
            format!(
                "origin {:?}, spacing {:?}, rotation {}; expected the isosurface's grid: origin {:?}, spacing {:?}, \
                 rotation {}",
                values.origin, values.spacing, values.rotation, vol.origin, vol.spacing, vol.rotation
            )
        },
    )?;
    let (mesh, grid) = welded(vol, tree, isovalue)?;
    let sampled = grid.iter().map(|&q| sample(values, q)).collect();
    values.take_error()?;
    Ok((mesh, sampled))
}

/// `vol`'s value at grid-frame point `q` (inside its box), trilinear over the corners of weight
/// above 0: a coordinate within 1e-9 of a sample plane (a vertex's two coordinates on its edge,
/// up to the rounding of `origin + i spacing`) is snapped to it, so a NaN sample beside the edge
/// does not leak in with a weight of 1e-16.
fn sample(vol: &Volume, q: [f64; 3]) -> f64 {
    let n = [vol.nx, vol.ny, vol.nz];
    let mut at = [0usize; 3];
    let mut t = [0.0f64; 3];
    for a in 0..3 {
        let last = (n[a] - 1) as f64;
        let f = ((q[a] - vol.origin[a]) / vol.spacing[a]).clamp(0.0, last);
        let (mut i, mut u) = (f.floor(), f - f.floor());
        if u > 1.0 - 1e-9 {
            (i, u) = ((i + 1.0).min(last), 0.0);
        } else if u < 1e-9 {
            u = 0.0;
        }
        (at[a], t[a]) = (i as usize, u);
    }
    let mut acc = 0.0;
    for corner in 0..8 {
        let mut w = 1.0;
        let mut p = at;
        for a in 0..3 {
            if corner >> a & 1 == 1 {
                w *= t[a];
                p[a] += 1;
            } else {
                w *= 1.0 - t[a];
            }
        }
        if w > 0.0 {
            acc += w * f64::from(vol.get(p[0], p[1], p[2]));
        }
    }
    acc + vol.offset
}

/// The welded mesh and each vertex's grid-frame position (before the rotation).
fn welded(vol: &Volume, tree: &MinMaxOctree, isovalue: f64) -> Result<(IsoMesh, Vec<[f64; 3]>)> {
    let w = vol.residual(isovalue, "isovalue")?;
    ensure(tree.cells() == [vol.nx as u32 - 1, vol.ny as u32 - 1, vol.nz as u32 - 1], "volume", || {
        "the octree was built from another volume".into()
    })?;
    // The renderer's default cull depth; any depth gives the same triangles (a node's patch is the
    // union of its cells'), this one only keeps patches and their order those the renderer makes.
    let depth = tree.max_depth().saturating_sub(2);
    let nodes = tree.straddling_at_depth(w, depth);
    let patches = extract_nodes(vol, w, &nodes);
    vol.take_error()?;
    let mut out = IsoMesh::default();
    let mut grid = Vec::new();
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let (c, s) = vol.cos_sin();
    for p in &patches {
        let remap: Vec<u32> = p
            .positions
            .iter()
            .zip(&p.normals)
            .map(|(q, n)| {
                *index.entry(q.map(f64::to_bits)).or_insert_with(|| {
                    out.vertices.push(vol.rotated((c, s), *q));
                    grid.push(*q);
                    out.normals.push([c as f32 * n[0] - s as f32 * n[1], s as f32 * n[0] + c as f32 * n[1], n[2]]);
                    (out.vertices.len() - 1) as u32
                })
            })
            .collect();
        out.faces.extend(p.triangles.iter().map(|t| t.map(|k| remap[k as usize])));
    }
    Ok((out, grid))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_mesh_is_closed_and_matches_the_patches() {
        let vol = super::super::sphere_field(20, 0.6);
        let tree = MinMaxOctree::build(&vol);
        let m = isosurface_mesh(&vol, &tree, 0.0).unwrap();
        let all = super::super::march::extract(&vol, 0.0, [0; 3], [19; 3]);
        assert_eq!(m.faces.len(), all.triangle_count());
        // Welded and closed: every edge is shared by exactly two triangles.
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for f in &m.faces {
            for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        assert!(edges.values().all(|&n| n == 2));
        for v in &m.vertices {
            let r = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            assert!((r - 0.6).abs() < 0.03, "{r}");
        }
        assert!(isosurface_mesh(&vol, &tree, f64::NAN).unwrap_err().to_string().starts_with("isovalue"));
    }

    #[test]
    fn sampled_values_interpolate_along_the_vertices_edges() {
        let vol = super::super::sphere_field(14, 0.6).with_rotation(30.0).unwrap();
        let tree = MinMaxOctree::build(&vol);
        let (o, s) = (vol.origin, vol.spacing);
        // A field linear in the grid frame (exact along an edge), with NaN on one side of the plane
        // x = 0.2 (between samples: some edges have one NaN end).
        let lin = |x: f64, y: f64, z: f64| 7.0 + 3.0 * x - 2.0 * y + 0.5 * z;
        let values =
            Volume::from_fn((14, 14, 14), o, s, |x, y, z| if x > 0.2 { f32::NAN } else { lin(x, y, z) as f32 })
                .unwrap()
                .with_rotation(30.0)
                .unwrap();
        let (m, v) = isosurface_mesh_sampled(&vol, &tree, 0.0, &values).unwrap();
        assert_eq!(m.faces, isosurface_mesh(&vol, &tree, 0.0).unwrap().faces);
        assert_eq!(v.len(), m.vertices.len());
        let (c, sn) = vol.cos_sin();
        let (mut finite, mut nan) = (0, 0);
        for (w, &got) in m.vertices.iter().zip(&v) {
            // Back to the grid frame: undo the rotation about the origin's vertical.
            let (u, t) = (w[0] - o[0], w[1] - o[1]);
            let q = [o[0] + c * u + sn * t, o[1] - sn * u + c * t, w[2]];
            // The x of the samples it is interpolated from: the two about it when its x is not on a
            // sample plane (an edge along x, or a loop's centre inside a cell), else the one it is
            // on; NaN beyond 0.2.
            let f = (q[0] - o[0]) / s[0];
            let xs = match (f - f.round()).abs() > 1e-6 {
                true => vec![o[0] + f.floor() * s[0], o[0] + (f.floor() + 1.0) * s[0]],
                false => vec![o[0] + f.round() * s[0]],
            };
            let ends_nan = xs.iter().any(|&x| x > 0.2);
            if ends_nan {
                assert!(got.is_nan(), "{q:?}: {got}");
                nan += 1;
            } else {
                // (The samples are f32.)
                assert!((got - lin(q[0], q[1], q[2])).abs() < 1e-5, "{q:?}: {got} vs {}", lin(q[0], q[1], q[2]));
                finite += 1;
            }
        }
        assert!(finite > 50 && nan > 50, "{finite} {nan}");
        // Another grid is refused, naming `values`.
        for other in [
            super::super::sphere_field(13, 0.6).with_rotation(30.0).unwrap(),
            super::super::sphere_field(14, 0.6),
            Volume::from_fn((14, 14, 14), [0.0; 3], s, |_, _, _| 0.0).unwrap().with_rotation(30.0).unwrap(),
        ] {
            let e = isosurface_mesh_sampled(&vol, &tree, 0.0, &other).unwrap_err().to_string();
            assert!(e.starts_with("values"), "{e}");
        }
    }

    #[test]
    fn rotation_turns_the_vertices_about_the_origin() {
        let vol = super::super::sphere_field(12, 0.5);
        let tree = MinMaxOctree::build(&vol);
        let a = isosurface_mesh(&vol, &tree, 0.0).unwrap();
        let turned = vol.clone().with_rotation(90.0).unwrap();
        let b = isosurface_mesh(&turned, &tree, 0.0).unwrap();
        assert_eq!(a.faces, b.faces);
        // origin (-1, -1): (x, y) -> (-1 - (y + 1), -1 + (x + 1))
        for (p, q) in a.vertices.iter().zip(&b.vertices) {
            assert_eq!([q[0], q[1], q[2]], [-1.0 - (p[1] + 1.0), -1.0 + (p[0] + 1.0), p[2]]);
        }
        assert!(vol.with_rotation(f64::INFINITY).unwrap_err().to_string().starts_with("rotation"));
    }
}

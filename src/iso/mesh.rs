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
    let w = vol.residual(isovalue, "isovalue")?;
    ensure(tree.cells() == [vol.nx as u32 - 1, vol.ny as u32 - 1, vol.nz as u32 - 1], "volume", || {
        "the octree was built from another volume".into()
    })?;
    // The renderer's default cull depth; any depth gives the same triangles (a node's patch is the
    // union of its cells'), this one only keeps patches and their order those the renderer makes.
    let depth = tree.max_depth().saturating_sub(2);
    let nodes = tree.straddling_at_depth(w, depth);
    let patches = extract_nodes(vol, w, &nodes);
    let mut out = IsoMesh::default();
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let (c, s) = vol.cos_sin();
    for p in &patches {
        let remap: Vec<u32> = p
            .positions
            .iter()
            .zip(&p.normals)
            .map(|(q, n)| {
                *index.entry(q.map(f64::to_bits)).or_insert_with(|| {
                    out.vertices.push(vol.to_world(*q));
                    out.normals.push([c as f32 * n[0] - s as f32 * n[1], s as f32 * n[0] + c as f32 * n[1], n[2]]);
                    (out.vertices.len() - 1) as u32
                })
            })
            .collect();
        out.faces.extend(p.triangles.iter().map(|t| t.map(|k| remap[k as usize])));
    }
    Ok(out)
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

//! Smooth vertex normals of triangle meshes, packed for the lit pass.
//!
//! Contract: [`smooth_normals`] gives one packed normal per input vertex (the area-weighted mean
//! of the normals of the faces that use it), or None when the mesh should keep facet shading: when
//! more than [`MAX_CREASE_FRACTION`] of its used vertices are creases (a face around the vertex
//! turns more than [`CREASE_DEGREES`] from the vertex normal: edges of boxes, flat caps, or faces
//! wound inconsistently, whose normals would cancel). Vertices used only by zero-area faces get
//! [`NONE`]. Every level of detail of a tile indexes the fine level's vertices, so a coarser level
//! interpolates the fine surface's normals and shades close to it, where facet normals of larger
//! triangles shade visibly differently; how close is each level's shading error
//! ([`super::shading`]), which the renderer bounds. A structured grid mesh shades every level from
//! these normals at its grid coordinates instead (`TileMesh::grid_uv`).
//!
//! Packing: octahedral, two snorm16 (`pack2x16snorm`: x in the low half), decoded by draw.wgsl;
//! [`NONE`] (0) means "no normal" (the lit pass then uses the facet's), so the one unit vector that
//! would encode as 0, +z, is stored one unit of the last place off.

use glam::DVec3;

/// A vertex without a normal.
pub const NONE: u32 = 0;
/// A face turning more than this from its vertex's normal makes the vertex a crease.
pub const CREASE_DEGREES: f64 = 60.0;
/// A mesh with more crease vertices than this fraction of its used vertices keeps facet shading.
pub const MAX_CREASE_FRACTION: f64 = 0.005;

/// Packed smooth normals, one per vertex, or None for facet shading (see the module doc).
pub fn smooth_normals(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Option<Vec<u32>> {
    // Per face its normal scaled by twice its area.
    let face_normals: Vec<DVec3> = faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|k| DVec3::from_array(vertices[k as usize]));
            (b - a).cross(c - a)
        })
        .collect();
    let mut sum = vec![DVec3::ZERO; vertices.len()];
    for (f, n) in faces.iter().zip(&face_normals) {
        for &k in f {
            sum[k as usize] += *n;
        }
    }
    let unit: Vec<Option<DVec3>> = sum.iter().map(|s| s.try_normalize()).collect();
    let cos_crease = CREASE_DEGREES.to_radians().cos();
    let mut crease = vec![false; vertices.len()];
    let mut used = vec![false; vertices.len()];
    for (f, n) in faces.iter().zip(&face_normals) {
        let n = n.try_normalize();
        for &k in f {
            used[k as usize] = true;
            // A vertex whose faces' normals cancel (inconsistent winding) is a crease too.
            if let Some(n) = n {
                crease[k as usize] |= unit[k as usize].is_none_or(|v| n.dot(v) < cos_crease);
            }
        }
    }
    let n_used = used.iter().filter(|&&u| u).count();
    let n_crease = crease.iter().filter(|&&c| c).count();
    if n_used == 0 || n_crease as f64 > MAX_CREASE_FRACTION * n_used as f64 {
        return None;
    }
    Some(unit.iter().map(|u| u.map_or(NONE, pack)).collect())
}

/// Octahedral encoding of a unit vector in two snorm16 (x in the low half); never [`NONE`].
pub fn pack(n: DVec3) -> u32 {
    let n = n / (n.x.abs() + n.y.abs() + n.z.abs());
    let (mut x, mut y) = (n.x, n.y);
    if n.z < 0.0 {
        let sgn = |v: f64| if v >= 0.0 { 1.0 } else { -1.0 };
        (x, y) = ((1.0 - n.y.abs()) * sgn(n.x), (1.0 - n.x.abs()) * sgn(n.y));
    }
    let q = |v: f64| ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16) as u16 as u32;
    let p = q(x) | (q(y) << 16);
    if p == NONE {
        1
    } else {
        p
    }
}

/// The unit vector of a packed normal (as draw.wgsl decodes it), None for [`NONE`].
pub fn unpack(p: u32) -> Option<DVec3> {
    if p == NONE {
        return None;
    }
    let s = |b: u32| ((b & 0xffff) as u16 as i16 as f64 / 32767.0).max(-1.0);
    let (x, y) = (s(p), s(p >> 16));
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        let sgn = |v: f64| if v >= 0.0 { 1.0 } else { -1.0 };
        ((1.0 - y.abs()) * sgn(x), (1.0 - x.abs()) * sgn(y))
    } else {
        (x, y)
    };
    DVec3::new(x, y, z).try_normalize()
}

/// For tests: the triangles of an `n` × `n` vertex sheet (vertex `j * n + i` at column i, row j),
/// two per cell, split from (i, j) to (i + 1, j + 1), wound counter-clockwise seen from +z.
#[cfg(test)]
pub(crate) fn sheet_faces(n: usize) -> Vec<[u32; 3]> {
    let mut f = Vec::with_capacity(2 * (n - 1) * (n - 1));
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let k = (j * n + i) as u32;
            f.push([k, k + 1, k + n as u32 + 1]);
            f.push([k, k + n as u32 + 1, k + n as u32]);
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_round_trips_within_a_thousandth() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(0.3, -0.5, 0.2),
            DVec3::new(-0.7, -0.1, -0.6),
            DVec3::new(1e-9, 0.0, -1.0),
        ] {
            let n = n.normalize();
            let back = unpack(pack(n)).unwrap();
            assert!(back.dot(n) > 1.0 - 1e-6, "{n} -> {back}");
        }
        assert_eq!(unpack(NONE), None);
    }

    /// A gently curved sheet is smooth: each vertex normal is the sheet's, for either winding
    /// of the whole sheet (the lit pass is two-sided).
    #[test]
    fn a_curved_sheet_is_smooth_and_a_box_is_not() {
        let n = 8;
        let mut v = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (i as f64, j as f64);
                v.push([x, y, 0.02 * x * x]);
            }
        }
        let f = sheet_faces(n);
        let packed = smooth_normals(&v, &f).unwrap();
        for (k, p) in packed.iter().enumerate() {
            let x = v[k][0];
            let expected = DVec3::new(-0.04 * x, 0.0, 1.0).normalize();
            assert!(unpack(*p).unwrap().dot(expected) > 0.999, "{k}");
        }
        // A cube: every vertex is a crease.
        let cube: Vec<[f64; 3]> =
            (0..8).map(|c| [(c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64]).collect();
        let quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
        let faces: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        assert_eq!(smooth_normals(&cube, &faces), None);
        // Inconsistent winding cancels normals: facet shading, not garbage.
        let mut flipped = f.clone();
        for t in flipped.iter_mut().step_by(2) {
            t.swap(1, 2);
        }
        assert_eq!(smooth_normals(&v, &flipped), None);
    }
}

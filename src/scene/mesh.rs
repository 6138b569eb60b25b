//! Triangle meshes (faults, isosurfaces, any surface): one tile, or about k spatially coherent
//! clusters, with QEM coarse proxies (`crate::lod::tile_mesh`).

use super::{check_coarse_factor, check_color, AddOptions, ObjectKind, Scene};
use crate::camera::MAX_COORD;
use crate::error::{ensure, num, Result};
use crate::lod;
use glam::DVec3;

impl Scene {
    /// Adds a triangle mesh. `vertices` is (n, 3) world coordinates, `faces` (m, 3) indices.
    /// `clusters` = None: one tile; Some(k): about k spatially coherent tiles.
    pub fn add_mesh(
        &mut self,
        vertices: &[[f64; 3]],
        faces: &[[i64; 3]],
        kind: &str,
        clusters: Option<usize>,
        mut opts: AddOptions,
    ) -> Result<u32> {
        let n = vertices.len();
        for (i, v) in vertices.iter().enumerate() {
            for (a, c) in v.iter().enumerate() {
                ensure(c.is_finite(), "vertices", || format!("vertices[{i}, {a}] is {c}; vertices must be finite"))?;
                ensure(c.abs() <= MAX_COORD, "vertices", || {
                    format!("vertices[{i}, {a}] is {}; coordinates must be within +-{MAX_COORD:e}", num(*c))
                })?;
            }
        }
        let mut f32faces: Vec<[u32; 3]> = Vec::with_capacity(faces.len());
        for (i, f) in faces.iter().enumerate() {
            for (a, &k) in f.iter().enumerate() {
                ensure(k >= 0 && (k as u64) < n as u64, "faces", || {
                    format!("faces[{i}, {a}] is {k}; indices must be in 0..{n}")
                })?;
            }
            f32faces.push(f.map(|k| k as u32));
        }
        if let Some(k) = clusters {
            ensure(k >= 1, "tiles", || format!("tiles is {k}; expected an integer >= 1 (or None for one tile)"))?;
        }
        let cf = check_coarse_factor(opts.coarse_factor)?;
        let color = check_color(opts.color, self.next_id)?;
        let color_by = super::color_by_arg(&opts.color, opts.color_by.take(), || None)?;
        if let Some(c) = &color_by {
            c.check(Some((n, &format!("one per vertex, {n}"))))?;
        }
        // Bounds of the referenced vertices only.
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for f in &f32faces {
            for &k in f {
                let p = DVec3::from_array(vertices[k as usize]);
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        if lo.x > hi.x {
            (lo, hi) = (DVec3::ZERO, DVec3::ZERO);
        }
        let o = self.origin_for(lo, hi);
        let k = clusters.unwrap_or(1).min(f32faces.len().max(1));
        let values = color_by.as_ref().and_then(|c| c.values.as_deref());
        // Smooth shading where the surface is smooth (faults, isosurfaces), facets elsewhere.
        let normals = lod::normals::smooth_normals(vertices, &f32faces);
        // A smooth structured grid (a fault sampled on a grid) shades every level from its grid.
        let grid_uv: Option<Vec<u32>> = normals
            .as_ref()
            .and_then(|_| lod::structured_grid(n, &f32faces))
            .map(|(nu, _)| (0..n).map(|k| (k % nu) as u32 | (((k / nu) as u32) << 16)).collect());
        let attrs = lod::VertexAttributes { values, normals: normals.as_deref(), grid_uv: grid_uv.as_deref() };
        let tiles = opts.interrupt.run_parallel(|stop| lod::tile_mesh(vertices, attrs, &f32faces, o, k, cf, stop))?;
        // The range of what is drawn: the vertices the faces use.
        let color_by = color_by.map(|c| c.resolve(super::tile_scalars(&tiles, o.z, &c.source))).transpose()?;
        Ok(self.push(o, opts.name, ObjectKind::Mesh { kind: kind.to_string() }, color, color_by, tiles))
    }
}

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
        opts: AddOptions,
    ) -> Result<u32> {
        check_vertices(vertices)?;
        let n = vertices.len();
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
        let k = clusters.unwrap_or(1).min(f32faces.len().max(1));
        let shape = Shape::of_mesh(vertices, &f32faces);
        self.add_tiled(vertices, shape, kind, opts, |attrs, o, cf, stop| {
            lod::tile_mesh(vertices, attrs, &f32faces, o, k, cf, stop)
        })
    }

    /// Adds the mesh of `vertices` (checked), whose bounds, normals and grid coordinates `shape`
    /// gives, as object kind `kind`, cut into tiles by `tile` (given the vertices' attributes, the
    /// object's origin, the coarse factor and the interrupt flag): the options are checked, the
    /// colouring resolved over what the tiles draw.
    pub(super) fn add_tiled(
        &mut self,
        vertices: &[[f64; 3]],
        shape: Shape,
        kind: &str,
        mut opts: AddOptions,
        tile: impl FnOnce(lod::VertexAttributes<'_>, DVec3, f32, &crate::error::Work) -> Vec<lod::TileMesh> + Send,
    ) -> Result<u32> {
        let n = vertices.len();
        let cf = check_coarse_factor(opts.coarse_factor)?;
        let color = check_color(opts.color, self.next_id)?;
        let color_by = super::color_by_arg(&opts.color, opts.color_by.take(), || None)?;
        if let Some(c) = &color_by {
            c.check(Some((n, &format!("one per vertex, {n}"))))?;
        }
        let o = self.origin_for(shape.lo, shape.hi);
        let values = color_by.as_ref().and_then(|c| c.values.as_deref());
        let (normals, grid_uv) = (shape.normals, shape.grid_uv);
        let attrs = lod::VertexAttributes { values, normals: normals.as_deref(), grid_uv: grid_uv.as_deref() };
        let tiles = opts.interrupt.run_parallel(|stop| tile(attrs, o, cf, stop))?;
        // The range of what is drawn: the vertices the faces use.
        let color_by = color_by.map(|c| c.resolve(super::tile_scalars(&tiles, o.z, &c.source))).transpose()?;
        Ok(self.push(o, opts.name, ObjectKind::Mesh { kind: kind.to_string() }, color, color_by, tiles))
    }
}

/// Every coordinate finite and within +-MAX_COORD, or an error naming `vertices[i, a]`.
pub(super) fn check_vertices(vertices: &[[f64; 3]]) -> Result<()> {
    // NaN fails the comparison: only a failing input takes the loop that names the coordinate.
    if vertices.iter().flatten().all(|c| c.abs() <= MAX_COORD) {
        return Ok(());
    }
    for (i, v) in vertices.iter().enumerate() {
        for (a, c) in v.iter().enumerate() {
            ensure(c.is_finite(), "vertices", || format!("vertices[{i}, {a}] is {c}; vertices must be finite"))?;
            ensure(c.abs() <= MAX_COORD, "vertices", || {
                format!("vertices[{i}, {a}] is {}; coordinates must be within +-{MAX_COORD:e}", num(*c))
            })?;
        }
    }
    Ok(())
}

/// What a mesh's tiling needs besides its vertices: the bounds of the vertices its faces use
/// (zeros for none), its packed smooth normals (None: facet shading) and, for a structured grid
/// with smooth normals, each vertex's grid coordinates (`TileMesh::grid_uv`).
pub(super) struct Shape {
    pub lo: DVec3,
    pub hi: DVec3,
    pub normals: Option<Vec<u32>>,
    pub grid_uv: Option<Vec<u32>>,
}

impl Shape {
    /// The shape of the mesh of `vertices` and `faces` (valid indices).
    pub fn of_mesh(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Self {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for f in faces {
            for &k in f {
                let p = DVec3::from_array(vertices[k as usize]);
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        if lo.x > hi.x {
            (lo, hi) = (DVec3::ZERO, DVec3::ZERO);
        }
        // Smooth shading where the surface is smooth (faults, isosurfaces), facets elsewhere.
        let normals = lod::normals::smooth_normals(vertices, faces);
        // A smooth structured grid (a fault sampled on a grid) shades every level from its grid.
        let grid_uv = normals
            .as_ref()
            .and_then(|_| lod::structured_grid(vertices.len(), faces))
            .map(|(nu, _)| grid_coords(nu, vertices.len()));
        Shape { lo, hi, normals, grid_uv }
    }
}

/// `i | j << 16` for vertex `j nu + i` of a structured grid, for each of its `n` vertices.
pub(super) fn grid_coords(nu: usize, n: usize) -> Vec<u32> {
    (0..n).map(|k| (k % nu) as u32 | (((k / nu) as u32) << 16)).collect()
}

//! Height fields (horizons, terrain): a (ny, nx) grid of heights cut into tiles of the grid, with
//! lattice or QEM coarse proxies (`crate::lod::tile_heightfield`).

use super::{check_coarse_factor, check_color, AddOptions, Object, ObjectKind, Scene};
use crate::camera::MAX_COORD;
use crate::error::{ensure, num, Result};
use crate::lod::{self, GridSpec};
use glam::DVec3;

impl Scene {
    /// Adds a height field. `z` is row-major (ny, nx): x along columns, y along rows. NaN samples
    /// (and samples equal to `null_value`) are holes; triangles touching a hole are dropped.
    #[allow(clippy::too_many_arguments)]
    pub fn add_heightfield(
        &mut self,
        z: &[f64],
        ny: usize,
        nx: usize,
        origin: [f64; 2],
        spacing: [f64; 2],
        tiles: (usize, usize),
        null_value: Option<f64>,
        opts: AddOptions,
    ) -> Result<u32> {
        ensure(nx >= 2 && ny >= 2, "z", || {
            format!("z has shape ({ny}, {nx}); a height field needs at least 2 x 2 samples")
        })?;
        ensure(z.len() == nx * ny, "z", || format!("z has {} values, expected {ny} x {nx}", z.len()))?;
        for (i, v) in origin.iter().enumerate() {
            ensure(v.is_finite(), "origin", || format!("component {i} is {v}; expected a finite number"))?;
        }
        for (i, v) in spacing.iter().enumerate() {
            ensure(v.is_finite() && *v > 0.0, "spacing", || {
                format!("component {i} is {v}; expected a finite number > 0")
            })?;
        }
        for (i, (o, (d, n))) in origin.iter().zip(spacing.iter().zip([nx, ny])).enumerate() {
            let end = o + d * (n - 1) as f64;
            ensure(
                o.abs() <= MAX_COORD && end.abs() <= MAX_COORD,
                if o.abs() > MAX_COORD { "origin" } else { "spacing" },
                || {
                    format!(
                        "component {i}: the grid spans {} .. {}; coordinates must be within +-{MAX_COORD:e}",
                        num(*o),
                        num(end)
                    )
                },
            )?;
        }
        let (tx, ty) = tiles;
        ensure(tx >= 1 && tx < nx, "tiles", || {
            format!("tiles[0] is {tx}; expected 1..={} for {nx} columns (each tile needs one cell)", nx - 1)
        })?;
        ensure(ty >= 1 && ty < ny, "tiles", || {
            format!("tiles[1] is {ty}; expected 1..={} for {ny} rows (each tile needs one cell)", ny - 1)
        })?;
        if let Some(nv) = null_value {
            ensure(!nv.is_infinite(), "null_value", || format!("null_value is {nv}; expected a finite number or NaN"))?;
        }
        let cf = check_coarse_factor(opts.coarse_factor)?;
        let color = check_color(opts.color, self.next_id)?;
        // Holes: NaN and null_value become NaN; infinities are an error.
        let mut zz: Vec<f64> = Vec::with_capacity(z.len());
        let (mut zmin, mut zmax) = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, &v) in z.iter().enumerate() {
            let v = if null_value.is_some_and(|nv| v == nv) { f64::NAN } else { v };
            ensure(!v.is_infinite(), "z", || {
                format!("z[{}, {}] is {v}; use NaN or null_value for holes", k / nx, k % nx)
            })?;
            ensure(v.is_nan() || v.abs() <= MAX_COORD, "z", || {
                format!("z[{}, {}] is {}; coordinates must be within +-{MAX_COORD:e}", k / nx, k % nx, num(v))
            })?;
            if v.is_finite() {
                zmin = zmin.min(v);
                zmax = zmax.max(v);
            }
            zz.push(v);
        }
        let (x0, y0) = (origin[0], origin[1]);
        let (dx, dy) = (spacing[0], spacing[1]);
        let (x1, y1) = (x0 + dx * (nx - 1) as f64, y0 + dy * (ny - 1) as f64);
        if zmin > zmax {
            (zmin, zmax) = (0.0, 0.0);
        }
        let o = self.origin_for(DVec3::new(x0, y0, zmin), DVec3::new(x1, y1, zmax));
        let grid = GridSpec { z: &zz, nx, ny, x0, y0, dx, dy };
        // Interruptible between tiles; on Err the scene is unchanged (the origin is set below).
        let tile_meshes = opts.interrupt.run_parallel(|stop| lod::tile_heightfield(&grid, o, (tx, ty), cf, stop))?;
        let kind = ObjectKind::Heightfield { nx, ny, x0: x0 - o.x, y0: y0 - o.y, dx, dy, tiles: (tx, ty) };
        Ok(self.push(o, opts.name, kind, color, tile_meshes))
    }
}

impl Object {
    /// The heights of a height field as a row-major (ny, nx) grid relative to the origin's z
    /// (NaN where no triangle uses the sample), rebuilt from the tiles' vertices: every vertex is
    /// a grid sample, and its origin-relative x, y give back its integer column and row.
    pub fn height_grid(&self) -> Option<Vec<f32>> {
        let ObjectKind::Heightfield { nx, ny, x0, y0, dx, dy, .. } = self.kind else { return None };
        let mut z = vec![f32::NAN; nx * ny];
        for t in &self.tiles {
            for p in &t.positions {
                let i = ((p[0] as f64 - x0) / dx).round();
                let j = ((p[1] as f64 - y0) / dy).round();
                if (0.0..nx as f64).contains(&i) && (0.0..ny as f64).contains(&j) {
                    z[j as usize * nx + i as usize] = p[2];
                }
            }
        }
        Some(z)
    }
}
